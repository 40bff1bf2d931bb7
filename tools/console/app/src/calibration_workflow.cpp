// SPDX-License-Identifier: Apache-2.0
#include "panoptes/console_app/calibration_workflow.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <deque>
#include <fstream>
#include <mutex>
#include <sstream>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "panoptes/calibration_history.h"
#include "panoptes/jsonl.h"

namespace panoptes::console {

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr std::size_t kLogLines = 14;
constexpr std::uintmax_t kMaxReportBytes = 4 << 20;

// The last lines of a step's log (what the CLI printed).
std::string tail_of(const fs::path& path, std::size_t lines) {
  std::ifstream file(path);
  std::deque<std::string> last;
  for (std::string line; std::getline(file, line);) {
    last.push_back(line.size() > 400 ? line.substr(0, 400) + "..." : line);
    if (last.size() > lines) last.pop_front();
  }
  std::string out;
  for (const std::string& line : last) out += line + "\n";
  return out;
}

std::string read_small(const fs::path& path) {
  std::error_code error;
  if (!fs::exists(path, error) || fs::file_size(path, error) > kMaxReportBytes) return {};
  std::ifstream file(path);
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

// Runs argv with stdout and stderr into `log`; returns the child's pid or -1.
pid_t spawn(const std::vector<std::string>& arguments, const fs::path& log) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  std::vector<char*> argv;
  argv.reserve(arguments.size() + 1);
  for (const std::string& argument : arguments) argv.push_back(const_cast<char*>(argument.c_str()));
  argv.push_back(nullptr);
  pid_t pid = -1;
  const int error = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  return error == 0 ? pid : -1;
}

}  // namespace

struct CalibrationWorkflow::Impl {
  CalibrationWorkflowOptions options;
  ConsoleState& state;
  std::mutex mutex;
  pid_t child = -1;
  std::string step = "idle";  // the running or last step: capture | floor_capture | solve | world
  std::string result;         // running | done | failed | stopped
  int exit_code = 0;
  bool stop_requested = false;
  std::string wand;
  json report;  // from the last solve
  std::string report_text;
  std::string world_text;
  std::uint64_t generation = 0;  // counts finished steps: the page fetches the report when it changes
  // The running capture's file, read as the capture writes it, for the live coverage.
  std::ifstream capture_file;
  std::streamoff capture_offset = 0;
  std::string capture_partial;
  std::uint64_t capture_bad_lines = 0;
  // versions(): the history index's time and size when last read, and what was read.
  std::string versions_stamp;
  json versions_cache;

  Impl(CalibrationWorkflowOptions options_in, ConsoleState& state_in)
      : options(std::move(options_in)), state(state_in) {}

  fs::path file(const std::string& name) const { return options.directory / name; }

  std::string start(const std::string& name, std::vector<std::string> arguments) {
    arguments.insert(arguments.begin(), options.estimator_node.string());
    child = spawn(arguments, file(name + ".log"));
    if (child < 0) return "cannot run " + options.estimator_node.string();
    step = name;
    result = "running";
    stop_requested = false;
    if (name == "capture" || name == "floor_capture") {
      state.start_coverage(wall_now_ns());
      capture_file = std::ifstream();
      capture_offset = 0;
      capture_partial.clear();
    }
    publish();
    return {};
  }

  // accept | revert of a version of the estimator's calibration file: done here, at once.
  std::string change_version(const CalibrationRequest& request) {
    if (options.calibration_file.empty())
      return "no calibration file: start panoptes_console with --calibration <the estimator's "
             "calibration.yaml>";
    try {
      CalibrationHistory history(options.calibration_file);
      if (request.action == "accept") {
        history.accept(request.version);
      } else {
        history.revert(request.version);
      }
    } catch (const std::exception& error) {
      return error.what();
    }
    publish();
    return {};
  }

  // The newest versions of the estimator's calibration file, oldest first (null: no file given),
  // read again when its history's index changed.
  json versions() {
    constexpr std::size_t kShown = 20;
    if (options.calibration_file.empty()) return nullptr;
    const CalibrationHistory history(options.calibration_file);
    std::error_code error;
    const fs::path index = history.directory() / "history.jsonl";
    const auto time = fs::last_write_time(index, error);
    const auto stamp = error ? std::string()
                             : std::to_string(time.time_since_epoch().count()) + "/" +
                                   std::to_string(fs::file_size(index, error));
    if (!stamp.empty() && stamp == versions_stamp) return versions_cache;
    json list = json::array();
    try {
      const auto all = history.versions();
      for (std::size_t i = all.size() > kShown ? all.size() - kShown : 0; i < all.size(); ++i)
        list.push_back(json::parse(version_json(all[i])));
    } catch (const std::exception& failure) {
      list = {{"error", failure.what()}};
    }
    versions_stamp = stamp;
    versions_cache = list;
    return list;
  }

  std::string handle(const CalibrationRequest& request) {
    std::lock_guard lock(mutex);
    if (request.action == "accept" || request.action == "revert") return change_version(request);
    if (request.action == "stop") {
      if (child < 0 || (step != "capture" && step != "floor_capture")) return "no capture is running";
      stop_requested = true;
      ::kill(child, SIGINT);
      return {};
    }
    if (child >= 0) return "the " + step + " step is still running";
    std::error_code error;
    fs::create_directories(options.directory, error);
    if (error) return options.directory.string() + ": " + error.message();
    if (request.action == "capture" || request.action == "floor_capture") {
      const std::string out = file(request.action == "capture" ? "wand.jsonl" : "floor.jsonl").string();
      std::vector<std::string> arguments = {"calibrate", "capture", "--out", out};
      if (!options.dds_profile.empty())
        arguments.insert(arguments.end(), {"--dds-profile", options.dds_profile});
      if (request.time_service) arguments.emplace_back("--time-service");
      return start(request.action, arguments);
    }
    if (request.action == "solve") {
      if (options.cameras_file.empty())
        return "no cameras file: start panoptes_console with --calibration-cameras <intrinsics.yaml> (step "
               "1)";
      if (!fs::exists(file("wand.jsonl"))) return "capture the wand first (step 2)";
      wand = request.wand;
      report = nullptr;
      report_text.clear();
      return start("solve", {"calibrate", "solve", "--cameras", options.cameras_file, "--in-features",
                             file("wand.jsonl").string(), "--wand", request.wand, "--out",
                             file("calibration.yaml").string(), "--time-offsets"});
    }
    // world: the wand laid on the floor (step 4c).
    if (!fs::exists(file("calibration.yaml"))) return "solve first (step 3)";
    if (!fs::exists(file("floor.jsonl"))) return "capture the wand on the floor first (step 4)";
    world_text.clear();
    char offset[32];
    std::snprintf(offset, sizeof offset, "%.4f", request.floor_offset_m);
    return start("world",
                 {"calibrate", "world", "--calibration", file("calibration.yaml").string(), "--in-features",
                  file("floor.jsonl").string(), "--wand", request.wand, "--wand-floor", "--floor-offset",
                  offset, "--out", file("calibration.yaml").string()});
  }

  // New complete lines of the capture file into the coverage (the CLI writes every 50 ms).
  void read_capture() {
    if (!capture_file.is_open()) {
      capture_file.open(file(step == "capture" ? "wand.jsonl" : "floor.jsonl"), std::ios::binary);
      if (!capture_file.is_open()) return;
    }
    capture_file.clear();
    capture_file.seekg(capture_offset);
    std::string chunk(1 << 16, '\0');
    while (capture_file.read(chunk.data(), static_cast<std::streamsize>(chunk.size())) ||
           capture_file.gcount() > 0) {
      const auto count = capture_file.gcount();
      capture_offset += count;
      capture_partial.append(chunk.data(), static_cast<std::size_t>(count));
    }
    std::size_t start = 0;
    for (auto end = capture_partial.find('\n'); end != std::string::npos;
         end = capture_partial.find('\n', start)) {
      const auto parsed = parse_feature_frame(std::string_view(capture_partial).substr(start, end - start));
      start = end + 1;
      if (!parsed.value) {
        ++capture_bad_lines;
        continue;
      }
      std::vector<BlobPoint> blobs;
      blobs.reserve(parsed.value->blobs.size());
      for (const auto& blob : parsed.value->blobs)
        blobs.push_back(
            {static_cast<float>(blob.x), static_cast<float>(blob.y), static_cast<float>(blob.area)});
      state.add_coverage_frame(parsed.value->camera_id, blobs);
    }
    capture_partial.erase(0, start);
  }

  void finished(int status) {
    child = -1;
    ++generation;
    exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    const bool capture = step == "capture" || step == "floor_capture";
    result = exit_code == 0 ? "done" : (capture && stop_requested ? "stopped" : "failed");
    if (capture) {
      read_capture();  // what the capture wrote last
      capture_file.close();
      state.stop_coverage();
    }
    if (step == "solve") {
      report = json::parse(read_small(file("calibration.report.json")), nullptr, false);
      if (report.is_discarded()) report = nullptr;
      report_text = read_small(file("calibration.report.txt"));
    }
    if (step == "world") world_text = read_small(file("calibration.world.txt"));
  }

  void publish() {
    json plots = json::array();
    std::error_code error;
    for (const auto& entry : fs::directory_iterator(options.directory, error)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("calibration.", 0) == 0 && entry.path().extension() == ".png") plots.push_back(name);
    }
    std::sort(plots.begin(), plots.end());
    const json job = {{"step", step},
                      {"result", result},
                      {"exit_code", exit_code},
                      {"log", step == "idle" ? "" : tail_of(file(step + ".log"), kLogLines)},
                      {"directory", options.directory.string()},
                      {"cameras_file", options.cameras_file},
                      {"have_wand", fs::exists(file("wand.jsonl"), error)},
                      {"have_floor", fs::exists(file("floor.jsonl"), error)},
                      {"have_calibration", fs::exists(file("calibration.yaml"), error)},
                      {"wand", wand},
                      {"plots", plots},
                      {"generation", generation},
                      {"capture_bad_lines", capture_bad_lines},
                      {"calibration_file", options.calibration_file.string()},
                      {"versions", versions()}};
    json full = job;
    full["report"] = report;
    full["report_text"] = report_text;
    full["world_text"] = world_text;
    state.set_calibration_job(job.dump(), full.dump());
  }

  void poll() {
    std::lock_guard lock(mutex);
    if (child >= 0) {
      if (step == "capture" || step == "floor_capture") read_capture();
      int status = 0;
      if (::waitpid(child, &status, WNOHANG) == child) finished(status);
    }
    publish();
  }
};

CalibrationWorkflow::CalibrationWorkflow(CalibrationWorkflowOptions options, ConsoleState& state)
    : impl_(std::make_unique<Impl>(std::move(options), state)) {
  impl_->publish();
}

CalibrationWorkflow::~CalibrationWorkflow() {
  std::lock_guard lock(impl_->mutex);
  if (impl_->child < 0) return;
  ::kill(impl_->child, SIGINT);
  for (int i = 0; i < 60; ++i) {
    int status = 0;
    if (::waitpid(impl_->child, &status, WNOHANG) == impl_->child) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ::kill(impl_->child, SIGKILL);
  ::waitpid(impl_->child, nullptr, 0);
}

std::string CalibrationWorkflow::handle(const CalibrationRequest& request) {
  return impl_->handle(request);
}

void CalibrationWorkflow::poll() {
  impl_->poll();
}

}  // namespace panoptes::console
