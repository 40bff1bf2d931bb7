// SPDX-License-Identifier: Apache-2.0
#include "panoptes/console_app/body_maker.h"

#include <fstream>
#include <mutex>
#include <sstream>
#include <string_view>
#include <utility>
#include <vector>

#include "panoptes/process.h"

namespace panoptes::console {

namespace {

// The child's outcome from its log: its last line that is a JSON object (the created body), else
// its last line naming the error (the CLI's message, "panoptes_ctl: " left out).
std::pair<std::string, std::string> read_outcome(const std::filesystem::path& log) {
  std::ifstream in(log);
  std::string line;
  std::string created;
  std::string error;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    if (line.front() == '{') {
      created = line;
    } else {
      error = line;
    }
  }
  constexpr std::string_view kPrefix = "panoptes_ctl: ";
  if (error.rfind(kPrefix, 0) == 0) error = error.substr(kPrefix.size());
  return {created, error};
}

}  // namespace

struct BodyMaker::Impl {
  BodyMakerOptions options;
  ConsoleState& state;
  std::mutex mutex;
  std::unique_ptr<ChildProcess> child;
  std::uint64_t client = 0;
  std::int64_t request = 0;
  std::string name;

  Impl(BodyMakerOptions options_in, ConsoleState& state_in)
      : options(std::move(options_in)), state(state_in) {}

  std::filesystem::path log() const { return options.work_dir / "body_create.log"; }

  std::string handle(const BodyCreateRequest& body, std::uint64_t from) {
    if (options.bodies_file.empty())
      return "this console has no bodies file: start panoptes_console with --bodies (the estimator's)";
    std::lock_guard lock(mutex);
    if (child) return "body '" + name + "' is being made: wait for it";
    std::vector<std::string> argv{options.ctl.string()};
    if (!options.dds_profile.empty()) {
      argv.emplace_back("--dds-profile");
      argv.push_back(options.dds_profile);
    }
    std::ostringstream timeout;
    timeout << options.timeout_s;
    argv.insert(argv.end(),
                {"--timeout", timeout.str(), "body", "create", "--name", body.name, "--bodies",
                 options.bodies_file.string(), "--frames", std::to_string(options.frames), "--tracks"});
    std::string ids;
    for (const std::int64_t id : body.tracks) {
      if (!ids.empty()) ids += ',';
      ids += std::to_string(id);
    }
    argv.push_back(ids);
    if (body.pivot) {
      argv.emplace_back("--pivot");
      argv.push_back(std::to_string(*body.pivot));
    }
    try {
      std::filesystem::create_directories(options.work_dir);
      child = std::make_unique<ChildProcess>("panoptes_ctl body create", std::move(argv), log());
    } catch (const std::exception& error) {
      return error.what();
    }
    client = from;
    request = body.request;
    name = body.name;
    return "";
  }

  void poll() {
    std::lock_guard lock(mutex);
    if (!child || child->running()) return;
    const int exit_code = child->exit_code();
    child.reset();
    const auto [created, error] = read_outcome(log());
    CommandOutcome outcome{client, request, CommandResult::kApplied, created};
    if (exit_code != kExitOk || created.empty()) {
      outcome.result = CommandResult::kRejected;
      outcome.reason = error.empty() ? "panoptes_ctl body create exited " + std::to_string(exit_code) : error;
    }
    state.on_outcome(std::move(outcome));
  }
};

BodyMaker::BodyMaker(BodyMakerOptions options, ConsoleState& state)
    : impl_(std::make_unique<Impl>(std::move(options), state)) {}

BodyMaker::~BodyMaker() = default;

std::string BodyMaker::handle(const BodyCreateRequest& request, std::uint64_t client) {
  return impl_->handle(request, client);
}

void BodyMaker::poll() {
  impl_->poll();
}

}  // namespace panoptes::console
