// SPDX-License-Identifier: Apache-2.0
#include "panoptes/process.h"

#include <execinfo.h>
#include <fcntl.h>
#include <pthread.h>
#include <spawn.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>

namespace panoptes {
namespace {
std::atomic<bool> g_stop{false};  // the one global: a signal handler can reach nothing else
extern "C" void on_stop_signal(int /*signal*/) {
  g_stop.store(true);
}
}  // namespace

void install_stop_handlers() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

double process_cpu_seconds() {
  timespec t{};
  if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t) != 0) return 0;
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

bool stop_requested() {
  return g_stop.load();
}
void request_stop() {
  g_stop.store(true);
}

ChildProcess::ChildProcess(std::string name, std::vector<std::string> argv,
                           const std::filesystem::path& log_file)
    : name_(std::move(name)) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  std::vector<char*> args;
  args.reserve(argv.size() + 1);  // and the terminating nullptr
  for (auto& a : argv) args.push_back(a.data());
  args.push_back(nullptr);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw std::runtime_error("cannot start " + argv[0] + ": " + std::strerror(rc));
  pid_ = pid;
}

ChildProcess::~ChildProcess() {
  stop();
}

bool ChildProcess::running() {
  if (pid_ <= 0) return false;
  int status = 0;
  if (waitpid(pid_, &status, WNOHANG) == pid_) {
    exit_status_ = status;
    pid_ = -1;
    return false;
  }
  return true;
}

int ChildProcess::stop(std::chrono::milliseconds timeout) {
  if (pid_ > 0) {
    kill(pid_, SIGINT);
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (running() && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      int status = 0;
      waitpid(pid_, &status, 0);
      exit_status_ = status;
      pid_ = -1;
    }
  }
  return exit_code();
}

int ChildProcess::exit_code() const {
  return WIFEXITED(exit_status_) ? WEXITSTATUS(exit_status_) : -1;
}

void detail::report_program_error(const char* program, const char* what) {
  std::fprintf(stderr, "%s: %s\n", program, what);
}

namespace {
const char* g_crash_program = "panoptes";  // set once, before the handlers exist

void write_text(const char* text) {
  ssize_t left = static_cast<ssize_t>(std::strlen(text));
  while (left > 0) {
    const ssize_t written = ::write(STDERR_FILENO, text, static_cast<std::size_t>(left));
    if (written <= 0) return;
    text += written;
    left -= written;
  }
}

// Only async-signal-safe calls: write, backtrace (loaded beforehand), backtrace_symbols_fd, raise.
extern "C" void on_fatal_signal(int signal) {
  write_text(g_crash_program);
  write_text(": fatal signal SIG");
  write_text(sigabbrev_np(signal) != nullptr ? sigabbrev_np(signal) : "?");
  write_text("; call stack (a frame in the program itself: addr2line -e <program> <+offset>):\n");
  void* frames[64];
  const int count = backtrace(frames, 64);
  backtrace_symbols_fd(frames, count, STDERR_FILENO);
  // The handler was installed with SA_RESETHAND: the signal raised again ends the process as before.
  raise(signal);
}
}  // namespace

namespace {
std::atomic<bool> g_stall_stack_written{false};

// The armed thread's call stack, asked for by end_within's watchdog (async-signal-safe calls only).
extern "C" void on_stall_stack_request(int /*signal*/) {
  void* frames[64];
  const int count = backtrace(frames, 64);
  backtrace_symbols_fd(frames, count, STDERR_FILENO);
  g_stall_stack_written.store(true);
}
}  // namespace

void end_within(std::chrono::milliseconds limit, int exit_code, const std::string& what) {
  static std::atomic<bool> armed{false};
  if (armed.exchange(true)) return;
  void* warm_up[1];
  backtrace(warm_up, 1);  // loads libgcc_s now, not in the handler
  const int stack_signal = SIGRTMIN + 4;
  struct sigaction action {};
  action.sa_handler = on_stall_stack_request;
  action.sa_flags = SA_RESTART;
  sigemptyset(&action.sa_mask);
  sigaction(stack_signal, &action, nullptr);
  char seconds[32];
  std::snprintf(seconds, sizeof(seconds), "%g", static_cast<double>(limit.count()) / 1000.0);
  const std::string message = std::string(g_crash_program) + ": " + what + " has not finished " + seconds +
                              " s after the work ended; ending now with exit code " +
                              std::to_string(exit_code) +
                              "; where it stalled (addr2line -f -C -e <program> <+offset>):\n";
  const pthread_t armed_thread = pthread_self();
  std::thread([limit, exit_code, armed_thread, stack_signal, message] {
    std::this_thread::sleep_for(limit);
    write_text(message.c_str());
    if (pthread_kill(armed_thread, stack_signal) == 0) {
      for (int i = 0; i < 200 && !g_stall_stack_written.load(); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    _exit(exit_code);
  }).detach();
}

void detail::install_crash_report(const char* program) {
  g_crash_program = program;
  void* warm_up[1];
  backtrace(warm_up, 1);  // its first call loads libgcc_s (malloc): not in a signal handler
  // A stack overflow has no stack left for the handler: it runs on one of its own (main thread).
  static char alternate_stack[64 * 1024];
  stack_t stack{};
  stack.ss_sp = alternate_stack;
  stack.ss_size = sizeof(alternate_stack);
  sigaltstack(&stack, nullptr);
  struct sigaction action {};
  action.sa_handler = on_fatal_signal;
  action.sa_flags = SA_RESETHAND | SA_ONSTACK;
  sigemptyset(&action.sa_mask);
  for (const int signal : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) sigaction(signal, &action, nullptr);
}

}  // namespace panoptes
