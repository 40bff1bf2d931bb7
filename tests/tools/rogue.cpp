// SPDX-License-Identifier: Apache-2.0
// panoptes_rogue: a hostile participant for tests (docs/hostile_input.md). It joins the domain like
// any program (loopback profile) and publishes malformed samples on every Panoptes topic: truncated
// CDR, a bad encapsulation header, strings and sequences with absurd lengths, strings without their
// terminator, NaN and infinity in every floating-point field, a FeatureFrame of 10^6 blobs, stamps
// an hour away, unknown camera ids, and a flood of bad camera commands. It never sends a sample a
// node should accept as genuine for a real camera (that is impersonation, which only the secure
// profile prevents), so the legitimate scene must track as well as without it.
//
// With --report-json it also reads camera_status and estimator_status on a second participant and
// writes the last counters of each node (those of the nodes, not its own fake status samples).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/cli.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/decode.h"
#include "panoptes/process.h"
#include "panoptes/time.h"
#include "panoptes_msgs/panoptes.h"

namespace {

namespace msg = panoptes::msg;
using Bytes = std::vector<std::uint8_t>;
using panoptes::TimeNs;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr TimeNs kHourNs = 3600 * panoptes::kNsPerSecond;
// 11 characters: with its NUL a leading string takes 16 bytes, and 16 without it too (the next
// member is aligned to 4 or 8), so dropping the terminator leaves the rest of the sample intact.
const std::string kRogueId = "rogue-id-11";

void put_u32(Bytes& cdr, std::size_t offset, std::uint32_t value) {
  if (offset + 4 > cdr.size()) return;
  for (int i = 0; i < 4; ++i) cdr[offset + i] = static_cast<std::uint8_t>(value >> (8 * i));  // little endian
}

// The malformed variants of one valid sample `cdr` (little endian, as encode_sample writes).
// `leading_string`: its first member is a string; `trailing_sequence`: its last member is a
// sequence, written empty, so its length is the last 4 bytes.
std::vector<std::pair<std::string, Bytes>> malformed_variants(const Bytes& cdr, bool leading_string,
                                                              bool trailing_sequence) {
  std::vector<std::pair<std::string, Bytes>> out;
  out.emplace_back("truncated",
                   Bytes(cdr.begin(), cdr.begin() + static_cast<std::ptrdiff_t>(cdr.size() / 2)));
  out.emplace_back("header_only", Bytes(cdr.begin(), cdr.begin() + 4));
  Bytes bad_header = cdr;
  bad_header[0] = 0xff;
  bad_header[1] = 0x7f;
  out.emplace_back("bad_encapsulation", bad_header);
  if (leading_string) {
    Bytes absurd = cdr;
    put_u32(absurd, 4, 0xfffffff0U);
    out.emplace_back("absurd_string_length", absurd);
    Bytes unterminated = cdr;  // the id is kRogueId: drop its NUL, the padding absorbs the byte
    put_u32(unterminated, 4, static_cast<std::uint32_t>(kRogueId.size()));
    unterminated[8 + kRogueId.size()] = 'X';
    out.emplace_back("unterminated_string", unterminated);
  }
  if (trailing_sequence) {
    Bytes absurd = cdr;
    put_u32(absurd, cdr.size() - 4, 0x7ffffff0U);
    out.emplace_back("absurd_sequence_length", absurd);
  }
  return out;
}

msg::Blob nan_blob() {
  msg::Blob blob;
  blob.x(static_cast<float>(kNaN));
  blob.y(static_cast<float>(kInf));
  blob.area(static_cast<float>(kNaN));
  blob.sum(static_cast<float>(-kInf));
  blob.m20(static_cast<float>(kNaN));
  blob.m11(static_cast<float>(kNaN));
  blob.m02(static_cast<float>(kNaN));
  return blob;
}

msg::Blob plausible_blob(int i) {
  msg::Blob blob;
  blob.x(100.0F + static_cast<float>(i % 500));
  blob.y(100.0F + static_cast<float>(i / 500 % 300));
  blob.area(12);
  blob.sum(2000);
  blob.peak(250);
  blob.m20(1);
  blob.m02(1);
  return blob;
}

msg::FeatureFrame feature_frame(const std::string& id, TimeNs stamp, std::vector<msg::Blob> blobs) {
  msg::FeatureFrame frame;
  frame.camera_id(id);
  frame.frame(1);
  frame.stamp_ns(stamp);
  frame.arrival_ns(stamp);
  frame.publish_ns(stamp);
  frame.blobs(std::move(blobs));
  return frame;
}

msg::Pose3 nan_pose() {
  msg::Pose3 pose;
  pose.position({kNaN, kInf, -kInf});
  pose.orientation({kNaN, kNaN, kNaN, kNaN});
  return pose;
}

// One writer per topic and the samples it sends each round.
struct Attack {
  std::string topic;
  std::unique_ptr<panoptes::dds::RawWriter> writer;
  std::vector<std::pair<std::string, Bytes>> samples;  // kind, CDR
};

template <class T>
void add_malformed(std::vector<std::pair<std::string, Bytes>>& samples, const T& valid, bool leading_string,
                   bool trailing_sequence) {
  for (auto& variant :
       malformed_variants(panoptes::dds::encode_sample(valid), leading_string, trailing_sequence))
    samples.push_back(std::move(variant));
}

template <class T>
void add_valid(std::vector<std::pair<std::string, Bytes>>& samples, const std::string& kind,
               const T& message) {
  samples.emplace_back(kind, panoptes::dds::encode_sample(message));
}

// The hostile samples of every topic that a node reads (features, camera info, commands,
// predictions, time sync) and, malformed only, of every other Panoptes topic.
std::map<std::string, std::vector<std::pair<std::string, Bytes>>> hostile_samples(
    const std::vector<std::string>& cameras, TimeNs now) {
  std::map<std::string, std::vector<std::pair<std::string, Bytes>>> by_topic;
  auto& features = by_topic["rt/panoptes/features"];
  add_malformed(features, feature_frame(kRogueId, now, {}), true, true);
  add_valid(features, "nan_blobs", feature_frame("rogue-nan", now, {nan_blob(), nan_blob()}));
  add_valid(features, "stamp_hour_ahead", feature_frame("rogue-ahead", now + kHourNs, {plausible_blob(0)}));
  add_valid(features, "stamp_hour_behind", feature_frame("rogue-behind", now - kHourNs, {plausible_blob(0)}));
  add_valid(features, "unknown_camera", feature_frame("rogue-unknown", now, {plausible_blob(0)}));
  add_valid(features, "bad_camera_id", feature_frame(std::string("rogue\x01\x02", 7), now, {}));
  // Above the estimator's max_blobs (4096): rejected whole. (The 10^6-blob frames of
  // --million-blob-frames are 40 MB: a best-effort reader usually loses some of their fragments.)
  std::vector<msg::Blob> many;
  for (int i = 0; i < 5000; ++i) many.push_back(plausible_blob(i));
  add_valid(features, "too_many_blobs", feature_frame("rogue-many", now, std::move(many)));

  auto& info = by_topic["rt/panoptes/camera_info"];
  msg::CameraInfo camera_info;
  camera_info.camera_id(kRogueId);
  add_malformed(info, camera_info, true, false);
  camera_info.camera_id("rogue-nan-info");
  camera_info.width(640);
  camera_info.height(480);
  camera_info.K({kNaN, kInf, kNaN, kNaN});
  camera_info.distortion({kNaN, kNaN, kNaN, kNaN, kNaN});
  camera_info.has_pose(true);
  camera_info.T_world_cam(nan_pose());
  add_valid(info, "nan_calibration", camera_info);

  auto& commands = by_topic["rt/panoptes/camera_command"];
  msg::CameraCommand command;
  command.target(kRogueId);
  add_malformed(commands, command, true, true);
  command.target("*");
  command.command("set_threshold");
  command.arguments({"nan"});
  add_valid(commands, "nan_argument", command);
  command.command("set_exposure");
  command.arguments({"inf"});
  add_valid(commands, "inf_argument", command);
  command.command("rogue_unknown_command");
  command.arguments({});
  add_valid(commands, "unknown_command", command);
  command.arguments(std::vector<std::string>(300, "1"));
  add_valid(commands, "too_many_arguments", command);

  auto& predictions = by_topic["rt/panoptes/predictions"];
  msg::Predictions prediction;
  prediction.camera_id(kRogueId);
  add_malformed(predictions, prediction, true, true);
  msg::PredictedWindow window;
  window.x(static_cast<float>(kNaN));
  window.y(static_cast<float>(kInf));
  window.half_width(static_cast<float>(kNaN));
  window.half_height(-1);
  prediction.windows({window});
  prediction.stamp_ns(now);
  for (const auto& id : cameras) {  // addressed to the real cameras: rejected there, not used
    prediction.camera_id(id);
    add_valid(predictions, "nan_windows", prediction);
  }

  auto& sync = by_topic["rt/panoptes/time_sync"];
  msg::TimeSync time_sync;
  time_sync.client_id(kRogueId);
  add_malformed(sync, time_sync, true, false);
  for (const auto& id : cameras) {  // replies an hour away to requests never sent
    time_sync.client_id(id);
    time_sync.seq(0xdeadbeef);
    time_sync.is_reply(true);
    time_sync.t1_ns(now - kHourNs);
    time_sync.t2_ns(now + kHourNs);
    time_sync.t3_ns(now + kHourNs);
    add_valid(sync, "reply_hour_away", time_sync);
  }

  msg::CameraStatus status;
  status.camera_id(kRogueId);
  add_malformed(by_topic["rt/panoptes/camera_status"], status, true, true);
  msg::CameraPreview preview;
  preview.camera_id(kRogueId);
  add_malformed(by_topic["rt/panoptes/camera_preview"], preview, true, true);
  add_malformed(by_topic["rt/panoptes/estimator_status"], msg::EstimatorStatus(), false, true);
  add_malformed(by_topic["rt/panoptes/tracks"], msg::TrackFrame(), false, true);
  msg::BodyPose body;
  body.name(kRogueId);
  add_malformed(by_topic["rt/panoptes/bodies"], body, true, false);
  add_malformed(by_topic["rt/panoptes/calibration"], msg::SystemCalibration(), false, true);
  add_malformed(by_topic["rt/panoptes/frames"], msg::MocapFrame(), false, true);
  add_malformed(by_topic["rt/panoptes/body_descriptions"], msg::BodyDescriptions(), false, true);
  msg::RecorderCommand recorder_command;
  recorder_command.target(kRogueId);
  add_malformed(by_topic["rt/panoptes/recorder_command"], recorder_command, true, false);
  msg::RecorderStatus recorder_status;
  recorder_status.recorder_id(kRogueId);
  add_malformed(by_topic["rt/panoptes/recorder_status"], recorder_status, true, false);
  return by_topic;
}

// The last counters the real nodes published (camera_status of the given cameras,
// estimator_status with finite figures: the rogue's own fake ones are NaN or malformed).
class StatusReport {
 public:
  StatusReport(panoptes::dds::Bus& bus, std::vector<std::string> cameras) : cameras_(std::move(cameras)) {
    camera_reader_ = bus.make_reader<msg::CameraStatus>([this](msg::CameraStatus&& status) {
      if (std::find(cameras_.begin(), cameras_.end(), status.camera_id()) == cameras_.end()) return;
      std::lock_guard<std::mutex> lock(mutex_);
      json_["camera_status"][status.camera_id()] = counters_of(status.counters());
    });
    estimator_reader_ = bus.make_reader<msg::EstimatorStatus>([this](msg::EstimatorStatus&& status) {
      if (status.stamp_ns() <= 0 || !std::isfinite(status.cpu_percent())) return;
      std::lock_guard<std::mutex> lock(mutex_);
      json_["estimator_status"] = counters_of(status.counters());
    });
  }
  nlohmann::json json() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return json_;
  }

 private:
  static nlohmann::json counters_of(const std::vector<msg::Counter>& counters) {
    nlohmann::json out = nlohmann::json::object();
    for (const auto& counter : counters) out[counter.name()] = counter.value();
    return out;
  }
  std::vector<std::string> cameras_;
  mutable std::mutex mutex_;
  nlohmann::json json_ = {{"camera_status", nlohmann::json::object()}, {"estimator_status", nullptr}};
  std::unique_ptr<panoptes::dds::Reader<msg::CameraStatus>> camera_reader_;
  std::unique_ptr<panoptes::dds::Reader<msg::EstimatorStatus>> estimator_reader_;
};

struct Options {
  double duration_s = 10;
  double rate_hz = 20;  // rounds per second: every hostile sample of every topic once
  int flood = 400;      // bad camera commands per round, in one burst
  int million_blob_frames = 2;
  std::vector<std::string> cameras;
  std::string report_json;
  std::string dds_profile;
  std::vector<std::string> topics;  // only these topics (empty: every one)
};

// Stops at `end`: a reliable writer whose readers are slow blocks in write() (up to its
// max_blocking_time per sample), and a loaded machine must not stretch --duration without bound.
std::uint64_t write_all(std::vector<Attack>& attacks, std::map<std::string, std::uint64_t>& sent,
                        std::chrono::steady_clock::time_point end) {
  std::uint64_t n = 0;
  for (auto& attack : attacks) {
    for (const auto& [kind, cdr] : attack.samples) {
      if (std::chrono::steady_clock::now() >= end) return n;
      if (attack.writer->write(cdr)) {
        ++sent[attack.topic + " " + kind];
        ++n;
      }
    }
  }
  return n;
}

int run(int argc, char** argv) {
  Options options;
  CLI::App app{"panoptes_rogue: publishes malformed samples on every Panoptes topic (tests only)",
               "panoptes_rogue"};
  app.option_defaults()->always_capture_default();
  app.add_option("--duration", options.duration_s, "seconds")->check(CLI::PositiveNumber);
  app.add_option("--rate", options.rate_hz, "rounds per second")->check(CLI::Range(0.1, 1000.0));
  app.add_option("--flood", options.flood, "bad camera commands per round")->check(CLI::Range(0, 100000));
  app.add_option("--million-blob-frames", options.million_blob_frames, "FeatureFrames of 10^6 blobs to send")
      ->check(CLI::Range(0, 10));
  app.add_option("--cameras", options.cameras, "the real cameras' ids (predictions, time sync, report)")
      ->delimiter(',');
  app.add_option("--report-json", options.report_json, "write the nodes' last status counters here");
  app.add_option("--dds-profile", options.dds_profile, "Fast DDS XML profile");
  app.add_option("--topics", options.topics,
                 "attack only these topics (e.g. rt/panoptes/calibration: with a DDS Security identity "
                 "not granted it, the writer is refused and the program exits 1)")
      ->delimiter(',')
      ->default_str("every Panoptes topic");
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv)) return *exit_code;
  panoptes::install_stop_handlers();
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // its lines reach a log even if it is killed
  std::printf("panoptes_rogue: attacking for %g s\n", options.duration_s);

  panoptes::dds::BusOptions bus_options;
  bus_options.profile_file = options.dds_profile;
  bus_options.participant_name = "panoptes_rogue";
  panoptes::dds::Bus bus(bus_options);
  // The report reads typed samples: a participant of its own (a topic has one type per participant).
  bus_options.participant_name = "panoptes_rogue/report";
  std::optional<panoptes::dds::Bus> report_bus;
  std::optional<StatusReport> report;
  if (!options.report_json.empty()) {
    report_bus.emplace(bus_options);
    report.emplace(*report_bus, options.cameras);
  }

  const auto attacked = [&options](const std::string& topic) {
    return options.topics.empty() ||
           std::find(options.topics.begin(), options.topics.end(), topic) != options.topics.end();
  };
  std::vector<Attack> attacks;
  for (auto& [topic, samples] : hostile_samples(options.cameras, panoptes::wall_now_ns())) {
    if (attacked(topic)) attacks.push_back({topic, bus.make_raw_writer(topic), std::move(samples)});
  }
  if (attacks.empty() && !options.topics.empty())
    throw std::runtime_error("--topics: no Panoptes topic among the ones given");
  if (!attacked("rt/panoptes/camera_command")) options.flood = 0;
  if (!attacked("rt/panoptes/features")) options.million_blob_frames = 0;
  auto flood_writer = options.flood > 0 ? bus.make_raw_writer("rt/panoptes/camera_command") : nullptr;
  msg::CameraCommand flood_command;
  flood_command.target("*");
  flood_command.command("rogue_flood");
  const Bytes flood_cdr = panoptes::dds::encode_sample(flood_command);
  auto million_writer =
      options.million_blob_frames > 0 ? bus.make_raw_writer("rt/panoptes/features") : nullptr;
  std::this_thread::sleep_for(std::chrono::seconds(1));  // discovery

  std::map<std::string, std::uint64_t> sent;
  std::uint64_t total = 0;
  const auto start = std::chrono::steady_clock::now();
  const auto end = start + std::chrono::duration_cast<std::chrono::nanoseconds>(
                               std::chrono::duration<double>(options.duration_s));
  const auto period = std::chrono::duration_cast<std::chrono::nanoseconds>(
      std::chrono::duration<double>(1.0 / options.rate_hz));
  int rounds = 0;
  int million_sent = 0;
  for (auto next = start; next < end && !panoptes::stop_requested(); next += period, ++rounds) {
    std::this_thread::sleep_until(next);
    // Stamps move with the wall clock, so "an hour away" stays an hour away.
    if (rounds % 20 == 0) {
      auto fresh = hostile_samples(options.cameras, panoptes::wall_now_ns());
      for (auto& attack : attacks) attack.samples = std::move(fresh[attack.topic]);
    }
    total += write_all(attacks, sent, end);
    for (int i = 0; i < options.flood && std::chrono::steady_clock::now() < end; ++i) {
      if (flood_writer->write(flood_cdr)) ++sent["rt/panoptes/camera_command flood"];
    }
    const bool million_due =
        million_sent < options.million_blob_frames &&
        next - start >= (million_sent + 1) * (end - start) / (options.million_blob_frames + 1);
    if (million_due) {
      std::vector<msg::Blob> blobs;
      blobs.reserve(1'000'000);
      for (int i = 0; i < 1'000'000; ++i) blobs.push_back(plausible_blob(i));
      const Bytes cdr =
          panoptes::dds::encode_sample(feature_frame("rogue-million", panoptes::wall_now_ns(), blobs));
      if (million_writer->write(cdr)) ++sent["rt/panoptes/features million_blobs"];
      ++million_sent;
    }
  }
  std::printf("panoptes_rogue: %d rounds, %llu samples written\n", rounds,
              static_cast<unsigned long long>(total));
  for (const auto& [what, n] : sent)
    std::printf("  %s: %llu\n", what.c_str(), static_cast<unsigned long long>(n));
  if (report) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // one more status period
    std::ofstream out(options.report_json);
    out << report->json().dump(2) << "\n";
    if (!out) {
      std::fprintf(stderr, "panoptes_rogue: cannot write %s\n", options.report_json.c_str());
      return 1;
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_rogue", [&] { return run(argc, argv); });
}
