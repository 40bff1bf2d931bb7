// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator_app/live_estimator.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>

#include "panoptes/calibration.h"
#include "panoptes/calibration_file.h"
#include "panoptes/calibration_history.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/convert.h"
#include "panoptes/dds/time_sync.h"
#include "panoptes/estimator/camera_ownership.h"
#include "panoptes/estimator_app/chain_messages.h"
#include "panoptes/estimator_app/frame_messages.h"
#include "panoptes/estimator_app/frame_periods.h"
#include "panoptes/estimator_app/latency_probe_echoer.h"
#include "panoptes/estimator_app/ros2_outputs.h"
#include "panoptes/estimator_app/status.h"
#include "panoptes/process.h"
#include "panoptes/session/frame_clock.h"
#include "panoptes/session/log.h"
#include "panoptes/session/output_sinks.h"

namespace panoptes::estimator_app {

namespace {

namespace est = panoptes::estimator;
using session::log;

std::unique_ptr<dds::Bus> open_bus(const LiveOptions& options) {
  dds::BusOptions bus_options;
  bus_options.profile_file = options.dds_profile;
  bus_options.security = options.security;
  bus_options.shared_memory = options.shared_memory;
  bus_options.participant_name = "estimator_node";
  auto bus = std::make_unique<dds::Bus>(bus_options);
  if (!options.quiet) log("DDS profile " + bus->profile_file().string());
  return bus;
}

// A file's modification time; none when it cannot be read (missing, no permission).
std::optional<std::filesystem::file_time_type> file_time(const std::string& path) {
  std::error_code error;
  const auto time = std::filesystem::last_write_time(path, error);
  if (error) return std::nullopt;
  return time;
}

// The DDS entities and the estimator thread's loop. Members are declared in the order they are
// created: the readers, whose listeners use what precedes them, go before the rest.
class LiveEstimator {
 public:
  LiveEstimator(const LiveOptions& options, session::EstimatorSession& session, session::BodyFile& body_file)
      : options_(options),
        node_(session.config().node),
        session_(session),
        tracker_(session.tracker()),
        body_file_(body_file),
        bus_(open_bus(options)),
        time_service_(*bus_),
        ownership_(seconds_to_ns(node_.camera_lost_after_s)),
        info_reader_(bus_->make_sourced_reader<msg::CameraInfo>(
            [this](msg::CameraInfo&& info, const dds::SampleSource& source) {
              if (!refuses_info(info, source)) announce(info);
            })),
        feature_reader_(bus_->make_sourced_reader<msg::FeatureFrame>(
            [this](msg::FeatureFrame&& message, const dds::SampleSource& source) {
              receive(std::move(message), source);
            })),
        track_writer_(bus_->make_writer<msg::TrackFrame>()),
        prediction_writer_(bus_->make_writer<msg::Predictions>()),
        status_writer_(bus_->make_writer<msg::EstimatorStatus>()),
        body_writer_(bus_->make_writer<msg::BodyPose>()),
        frame_writer_(bus_->make_writer<msg::MocapFrame>()),
        descriptions_writer_(bus_->make_writer<msg::BodyDescriptions>()),
        calibration_writer_(bus_->make_writer<msg::SystemCalibration>()) {
    if (options_.chains) chain_writer_ = bus_->make_writer<msg::ChainFrame>();
    if (options_.labels) {
      labels_writer_ = bus_->make_writer<msg::MarkerLabels>();
      labels_writer_->write(to_labels_message(*options_.labels));  // the subjects, before any name
      options_.labels->run_in_background();  // a revision search delays no frame (marker_sets.md)
    }
    if (options_.latency_probe) {
      latency_probe_.emplace(*bus_);
      log("benchmark aid: echoing latency probes (rt/panoptes/latency_probe/...)");
    }
    outputs_.emplace(options_.out_tracks, options_.out_poses);
    if (session.config().ros2.enabled) ros2_.emplace(*bus_, session.config().ros2);
    if (node_.fixed_rate_live()) {
      frame_clock_.emplace(node_.frame_rate_hz);
      if (!options_.quiet)
        log("rt/panoptes/frames at a fixed " + std::to_string(node_.frame_rate_hz) + " Hz (docs/frames.md)");
    }
    if (!options_.calibration_file.empty()) {
      calibration_file_time_ = file_time(options_.calibration_file);
      in_use_ = load_calibration(options_.calibration_file);
      for (const auto& camera : in_use_.cameras) from_file_.insert(camera.id);
    }
    publish_calibration();
  }

  int run();

 private:
  // A frame's output in order of urgency: its poses right after the update (what applications
  // wait for); then, once no other frame is due, its TrackFrame, the predictions for its camera's
  // next frame, the files and the latency trace. So a frame that arrives while the previous one is
  // being processed waits for that update only, not for its housekeeping (issue 7, bench_latency).
  struct Processed {
    FeatureFrame frame;
    std::vector<TrackRecord> tracks;  // at its update
    std::vector<PoseRecord> poses;
    LatencyProbeEchoer::Stamps stamps;  // --latency-probe
    session::FrameOutput output;        // what rt/panoptes/frames carried
  };

  // A DDS listener thread: a FeatureFrame goes to the session unless a second writer sent it.
  void receive(msg::FeatureFrame&& message, const dds::SampleSource& source);
  // CameraInfo from a writer other than the owner of its camera id (while the owner sends).
  bool refuses_info(const msg::CameraInfo& info, const dds::SampleSource& source);
  void announce(const msg::CameraInfo& info);
  void apply_announced_cameras();
  // Updates the tracker with frames taken from the inbox together (late ones in one replay).
  void update(std::vector<FeatureFrame>& due);
  // The outputs of one in-order frame right after its update (taken from the inbox at `dequeued_ns`).
  void publish_update(FeatureFrame&& frame, TimeNs dequeued_ns);
  // --frames fixed: the frame of the newest grid instant, once it is due (docs/frames.md).
  void publish_fixed_frame();
  // --frames fixed, before each update: the next instant's frame first if the update would overrun it.
  void hold_for_instant();
  // --frames fixed: the next instant falls due within `work_ns` (work that long waits until after it).
  bool near_instant(TimeNs work_ns) const;
  // The calibration in use (the file's cameras and those calibrated from their CameraInfo) on
  // rt/panoptes/calibration, transient-local: late joiners (the console, clients) get it at once.
  void publish_calibration() { calibration_writer_->write(dds::to_message(in_use_, wall_now_ns())); }
  void use_realtime_priority();
  // How long the loop may wait for frames: until the next fixed-rate instant, at most 1 ms.
  std::chrono::nanoseconds max_wait() const;
  void finish(Processed& done);
  bool finish_processed(bool force);
  void publish_predictions(const FeatureFrame& frame);
  void publish_status(TimeNs now, TimeNs start);
  // When the loop's periodic chores are next due.
  struct Chores {
    TimeNs next_status = 0;
    TimeNs next_body_poll = 0;
    TimeNs next_health_check = 0;
  };
  void do_chores(Chores& chores, TimeNs now, TimeNs start);
  // No frame for longer than a track lives without one (every camera stopped): the tracks go.
  void expire_idle_tracks(TimeNs now);
  void publish_descriptions_if_changed();
  // --subjects: the names on rt/panoptes/labels when the labelling stage's map changed.
  void publish_labels_if_changed();
  // --subjects: each marker's subject and name in a frame's output (rt/markers carries them), and
  // the segments' poses among its bodies.
  void name_markers(session::FrameOutput& output) const;
  // --continuous-calibration correct: each camera pose the tracker corrected is logged, becomes the
  // calibration in use (rt/panoptes/calibration) and, with a calibration file, a new version of it.
  void apply_corrections();
  void publish_chains(const FeatureFrame& frame);

  const LiveOptions& options_;
  const session::NodeSettings& node_;
  session::EstimatorSession& session_;
  est::Tracker& tracker_;
  session::BodyFile& body_file_;
  std::unique_ptr<dds::Bus> bus_;
  // The common time base is this process's clock: camera nodes synchronise to it (architecture.md "Time").
  dds::TimeSyncServer time_service_;
  std::mutex info_mutex_;
  std::vector<CameraCalibration> announced_;              // from CameraInfo, applied on the estimator thread
  std::map<std::string, std::uint64_t> info_rejections_;  // CameraInfo dropped, by reason
  // Which DDS writer speaks for each camera id: a second one is refused (docs/estimator.md).
  est::CameraOwnership ownership_;
  std::unique_ptr<dds::Reader<msg::CameraInfo>> info_reader_;
  std::unique_ptr<dds::Reader<msg::FeatureFrame>> feature_reader_;
  std::unique_ptr<dds::Writer<msg::TrackFrame>> track_writer_;
  std::unique_ptr<dds::Writer<msg::Predictions>>
      prediction_writer_;  // for every camera: beyond the cap below
  // One per camera, in its DDS partition, so that a camera reads its own predictions only
  // (docs/security.md); created at its first prediction, whose first few samples are lost.
  std::map<std::string, std::unique_ptr<dds::Writer<msg::Predictions>>> camera_prediction_writers_;
  static constexpr std::size_t kMaxPredictionWriters = 256;
  std::unique_ptr<dds::Writer<msg::EstimatorStatus>> status_writer_;
  std::unique_ptr<dds::Writer<msg::BodyPose>> body_writer_;
  std::unique_ptr<dds::Writer<msg::MocapFrame>> frame_writer_;
  std::unique_ptr<dds::Writer<msg::BodyDescriptions>> descriptions_writer_;
  std::unique_ptr<dds::Writer<msg::SystemCalibration>> calibration_writer_;
  SystemCalibration in_use_;
  // Drift refinements (continuous calibration) are written and published together, at most once
  // per kDriftVersionInterval: the cameras refined since the last version, and the worst residual.
  static constexpr TimeNs kDriftVersionIntervalNs = 60 * kNsPerSecond;
  std::set<std::string> drift_pending_;
  double drift_pending_rms_px_ = 0.0;
  TimeNs drift_written_ns_ = 0;
  void write_version(const std::string& reason, const std::vector<std::string>& cameras, double rms_px);
  // The calibration file's modification time when last read or written by this estimator; a
  // different one means someone else changed it (reload_calibration_if_changed).
  std::optional<std::filesystem::file_time_type> calibration_file_time_;
  void reload_calibration_if_changed();
  std::unique_ptr<dds::Writer<msg::ChainFrame>> chain_writer_;     // with options_.chains
  std::unique_ptr<dds::Writer<msg::MarkerLabels>> labels_writer_;  // with options_.labels
  std::uint64_t labels_generation_ = 0;                            // the map last written
  session::FrameOutputBuilder frame_builder_;
  std::optional<session::FrameClock> frame_clock_;  // --frames fixed
  session::FixedRateStats fixed_rate_stats_;
  // How long one frame's update and outputs take: a high-water mark that decays by 1/64 per update,
  // within 50 us..1 ms (hold_for_instant).
  struct WorkEstimate {
    TimeNs ns = 150'000;
    void add(TimeNs took) { ns = std::clamp<TimeNs>(std::max(took, ns - ns / 64), 50'000, 1'000'000); }
  } update_work_;
  WorkEstimate finish_work_;  // one processed frame's finish (tracks, predictions, files)
  std::uint64_t holds_ = 0;   // updates that waited for an instant
  // What the loop was doing when a fixed-rate frame fell due, for frames written more than 2 % of
  // a period after their instant (the end-of-run line; docs/frames.md, "Timing of the live loop").
  enum Phase : std::size_t { kWaiting, kUpdating, kFinishing, kHousekeeping, kPhases };
  Phase phase_ = kWaiting;
  std::array<std::uint64_t, kPhases> late_by_phase_{};
  session::FrameStages newest_stages_;  // of the newest processed frame (fixed-rate frames)
  std::size_t cameras_lost_ = 0;        // at the last health check: a change publishes the status at once
  std::uint64_t descriptions_generation_ = 0;  // the bodies file's generation last published
  std::uint64_t descriptions_sent_ = 0;        // BodyDescriptions.generation: 1, 2, ... per run
  std::map<std::string, int> segment_ids_;     // the segments' ids in the descriptions last written
  std::optional<LatencyProbeEchoer> latency_probe_;
  std::optional<Ros2Outputs> ros2_;  // docs/ros2.md
  std::optional<session::JsonlOutputs> outputs_;
  std::set<std::string> from_file_;
  std::set<std::string> announced_moving_;  // logged once each
  FramePeriods periods_;
  std::vector<Processed> processed_;  // finished from the front; cleared (capacity kept) when all are
  TimeNs unfinished_since_ns_ = 0;    // when the oldest unfinished one was processed
  struct StatusPoint {
    TimeNs wall_ns = 0;
    std::uint64_t replays = 0, replayed_frames = 0;
    double cpu_s = 0;
  } last_status_;  // for the rates over the last status period
  std::size_t finished_ = 0;
  TimeNs last_frame_wall_ns_ = 0;  // when frames were last taken from the inbox
};

void LiveEstimator::announce(const msg::CameraInfo& info) {
  if (const std::string_view problem = dds::camera_info_problem(info); !problem.empty()) {
    std::lock_guard<std::mutex> lock(info_mutex_);
    ++info_rejections_["camera_info_" + std::string(problem)];
    return;
  }
  if (auto calibration = dds::calibration_from(info); calibration && calibration->T_world_cam) {
    std::lock_guard<std::mutex> lock(info_mutex_);
    announced_.push_back(*calibration);
  }
}

void LiveEstimator::apply_announced_cameras() {
  std::lock_guard<std::mutex> lock(info_mutex_);
  for (const auto& camera : announced_) {
    // A moving camera's pose is its mount on a rig, not a fixed view (docs/inside_out.md): inside-out
    // tracking needs it in the calibration file with the landmarks.
    if (camera.moving && from_file_.count(camera.id) == 0) {
      if (announced_moving_.insert(camera.id).second)
        log("camera '" + camera.id +
            "' announces itself moving: not a fixed camera (inside-out needs it in --calibration with "
            "--landmarks)");
      continue;
    }
    // The calibration file wins over what a camera announces about itself.
    if (from_file_.count(camera.id) == 0 && !tracker_.has_camera(camera.id)) {
      tracker_.set_camera(camera);
      if (options_.chains) options_.chains->add_camera(camera);
      log("camera '" + camera.id + "' calibrated from its CameraInfo");
      in_use_.cameras.push_back(camera);
      publish_calibration();
    }
  }
  announced_.clear();
}

void LiveEstimator::publish_predictions(const FeatureFrame& frame) {
  const TimeNs next = periods_.next_stamp(frame.camera_id, frame.stamp_ns);
  if (!node_.predictions || next == frame.stamp_ns) return;
  msg::Predictions message;
  message.camera_id(frame.camera_id);
  message.stamp_ns(next);
  for (const auto& w : tracker_.predicted_windows(frame.camera_id, next, node_.prediction_margin_px)) {
    msg::PredictedWindow window;
    window.track_id(w.track_id);
    window.x(static_cast<float>(w.x));
    window.y(static_cast<float>(w.y));
    window.half_width(static_cast<float>(w.half_width));
    window.half_height(static_cast<float>(w.half_height));
    message.windows().push_back(window);
  }
  auto writer = camera_prediction_writers_.find(frame.camera_id);
  if (writer == camera_prediction_writers_.end() &&
      camera_prediction_writers_.size() < kMaxPredictionWriters) {
    writer = camera_prediction_writers_
                 .emplace(frame.camera_id,
                          bus_->make_writer<msg::Predictions>(dds::Qos::kDefault, {}, frame.camera_id))
                 .first;
  }
  (writer != camera_prediction_writers_.end() ? *writer->second : *prediction_writer_).write(message);
}

void LiveEstimator::update(std::vector<FeatureFrame>& due) {
  phase_ = kUpdating;
  TimeNs dequeued_ns = wall_now_ns();
  TimeNs started_ns = dequeued_ns;
  session_.process_due(
      due,
      [&](FeatureFrame& frame, est::FrameOutcome outcome) {
        if (outcome == est::FrameOutcome::kProcessed) publish_update(std::move(frame), dequeued_ns);
        update_work_.add(wall_now_ns() - started_ns);
        publish_fixed_frame();        // an instant that fell due during this update goes out before the next
        dequeued_ns = wall_now_ns();  // the next frame's update starts now
      },
      [&] {
        hold_for_instant();
        started_ns = wall_now_ns();
      });
  apply_corrections();
}

// An update that would still run at the next fixed-rate instant waits for it: the frame goes out at
// its instant from the state before the update, rather than up to an update late (docs/frames.md,
// "Timing of the live loop"). Spun, not slept: at most update_work_.ns, 1 ms.
void LiveEstimator::hold_for_instant() {
  if (!near_instant(update_work_.ns)) return;
  const TimeNs instant = frame_clock_->next_instant();
  if (wall_now_ns() < instant) ++holds_;
  while (wall_now_ns() < instant) {
  }
  publish_fixed_frame();
}

bool LiveEstimator::near_instant(TimeNs work_ns) const {
  return frame_clock_ && frame_clock_->next_instant() != 0 &&
         frame_clock_->next_instant() - wall_now_ns() <= work_ns;
}

void LiveEstimator::apply_corrections() {
  // Each quarantine's start and end with its capture stamp (the detection's time, which the status
  // line gives only as "quarantined 0.4 s", once a second).
  for (const auto& t : tracker_.take_calibration_transitions()) {
    if (options_.quiet) continue;
    log("calibration " + t.camera_id +
        (t.quarantined ? ": quarantined at capture stamp " : ": released at capture stamp ") +
        std::to_string(t.stamp_ns) + (t.quarantined ? " (" + t.reason + ")" : ""));
  }
  const auto corrections = tracker_.take_calibration_corrections();
  const TimeNs now = wall_now_ns();
  bool bumped = false;
  for (const auto& c : corrections) {
    using Kind = estimator::CalibrationCorrection::Kind;
    const bool drift = c.kind == Kind::kDrift;
    const bool settle = c.kind == Kind::kSettle;
    char text[240];
    std::snprintf(text, sizeof text,
                  "calibration %s: %s: turned %.3f deg, moved %.1f mm (%zu blobs on tracks, %.2f px RMS)",
                  c.camera_id.c_str(),
                  drift    ? "drift followed from the tracks"
                  : settle ? "pose after its bump refined over the tracks since"
                           : "pose corrected from the tracks the other cameras see",
                  c.result.rotation_change_deg, c.result.translation_change_mm, c.result.inliers,
                  c.result.rms_px);
    log(text);
    for (auto& camera : in_use_.cameras)
      if (camera.id == c.camera_id) camera.T_world_cam = c.after;
    if (drift) {
      drift_pending_.insert(c.camera_id);
      drift_pending_rms_px_ = std::max(drift_pending_rms_px_, c.result.rms_px);
      continue;
    }
    bumped = true;
    write_version(c.camera_id + (settle ? " refined after its bump correction (continuous calibration)"
                                        : " corrected after a bump (continuous calibration)"),
                  {c.camera_id}, c.result.rms_px);
  }
  const bool drift_due = !drift_pending_.empty() && now - drift_written_ns_ >= kDriftVersionIntervalNs;
  if (drift_due) {
    std::string names;
    for (const auto& id : drift_pending_) names += (names.empty() ? "" : ", ") + id;
    write_version("drift followed on " + names + " (continuous calibration)",
                  {drift_pending_.begin(), drift_pending_.end()}, drift_pending_rms_px_);
    drift_pending_.clear();
    drift_pending_rms_px_ = 0.0;
    drift_written_ns_ = now;
  }
  if (bumped || drift_due) publish_calibration();
}

void LiveEstimator::write_version(const std::string& reason, const std::vector<std::string>& cameras,
                                  double rms_px) {
  if (options_.calibration_file.empty()) return;
  const std::string who = cameras.size() == 1 ? cameras.front() : "cameras";
  try {
    CalibrationHistory history(options_.calibration_file);
    const CalibrationVersion version = history.record(
        in_use_, change_because(reason, cameras, std::numeric_limits<double>::quiet_NaN(), rms_px));
    calibration_file_time_ = file_time(options_.calibration_file);  // our own change: no reload
    log("calibration " + who + ": written to " + options_.calibration_file + " as version " +
        std::to_string(version.version) + " (estimator_node calibrate revert --calibration " +
        options_.calibration_file + " --version " + std::to_string(version.version - 1) + " undoes it)");
  } catch (const std::exception& e) {
    log("calibration " + who + ": the correction is in use but was not written to " +
        options_.calibration_file + ": " + e.what());
  }
}

void LiveEstimator::publish_update(FeatureFrame&& frame, TimeNs dequeued_ns) {
  const TimeNs updated_ns = wall_now_ns();
  auto poses = session_.current_poses();
  // Stamped before writing, like every publish_ns: delivery may complete within write().
  const TimeNs poses_published_ns = latency_probe_ && !poses.empty() ? wall_now_ns() : 0;
  for (const auto& pose : poses) {
    const msg::BodyPose pose_message = dds::to_message(pose);
    body_writer_->write(pose_message);
    if (latency_probe_) latency_probe_->note_pose(pose_message);
  }
  publish_chains(frame);
  auto tracks = tracker_.current_tracks();
  if (options_.labels) {
    options_.labels->observe(tracker_, tracks);
    publish_labels_if_changed();
  }
  const session::FrameStages stages{frame.arrival_ns,  frame.processing_ns, frame.publish_ns,
                                    frame.received_ns, dequeued_ns,         updated_ns};
  session::FrameOutput output;
  if (frame_clock_) {
    newest_stages_ = stages;
  } else {
    output = frame_builder_.build(tracker_, frame, stages, poses, tracks);
    name_markers(output);
    frame_writer_->write(to_frame_message(output, wall_now_ns()));
  }
  const LatencyProbeEchoer::Stamps stamps{dequeued_ns, updated_ns, poses_published_ns,
                                          poses.empty() ? 0 : poses.front().stamp_ns,
                                          static_cast<std::uint32_t>(poses.size())};
  if (processed_.size() == finished_) unfinished_since_ns_ = wall_now_ns();
  processed_.push_back({std::move(frame), std::move(tracks), std::move(poses), stamps, std::move(output)});
}

void LiveEstimator::publish_fixed_frame() {
  // Instants are on the common time base, which is this process's clock (architecture.md "Time").
  if (!frame_clock_ || tracker_.last_stamp_ns() == 0) return;
  // No frames from any camera for camera_lost_after_s: no frames out either (a client sees the
  // stream stop, as with a stopped commercial system, not coasting predictions that age).
  const TimeNs now = wall_now_ns();
  if (now - last_frame_wall_ns_ > seconds_to_ns(node_.camera_lost_after_s)) {
    frame_clock_->idle_until(now);
    return;
  }
  const auto tick = frame_clock_->latest_due(now);
  if (!tick) return;
  const auto tracks = tracker_.tracks_at(tick->instant_ns);
  const auto poses = session_.poses_at(tick->instant_ns);
  session::FrameOutput output =
      frame_builder_.build_at(tracker_, tick->frame_number, tick->instant_ns, newest_stages_, poses, tracks);
  name_markers(output);
  const TimeNs publish_ns = wall_now_ns();
  frame_writer_->write(to_frame_message(output, publish_ns));
  if (ros2_) ros2_->publish(output);
  // The data age only while the cameras send (not over the camera_lost_after_s before the stream stops).
  constexpr TimeNs kSendingNs = 50'000'000;
  const bool sending = now - last_frame_wall_ns_ <= kSendingNs;
  fixed_rate_stats_.add(sending ? tick->instant_ns - tracker_.last_stamp_ns() : -1,
                        publish_ns - tick->instant_ns);
  if (static_cast<double>(publish_ns - tick->instant_ns) > 0.02 * frame_clock_->period_ns())
    ++late_by_phase_[phase_];
}

std::chrono::nanoseconds LiveEstimator::max_wait() const {
  const std::chrono::nanoseconds most = std::chrono::milliseconds(1);
  if (!frame_clock_ || frame_clock_->next_instant() == 0) return most;
  // The last 200 us before an instant are spun, not slept: a wake-up from a timed wait on a busy
  // 2-core machine was measured up to 0.5 ms late (docs/frames.md, "Timing").
  constexpr TimeNs kSpinNs = 200'000;
  const TimeNs until = frame_clock_->next_instant() - wall_now_ns() - kSpinNs;
  return std::clamp(std::chrono::nanoseconds(until), std::chrono::nanoseconds(0), most);
}

// Chains right after the poses: their grab events are what an application waits for.
void LiveEstimator::publish_chains(const FeatureFrame& frame) {
  if (!options_.chains || !options_.chains->observe(frame, tracker_)) return;
  msg::ChainFrame message = to_chain_message(*options_.chains, frame);
  message.publish_ns(wall_now_ns());
  chain_writer_->write(message);
}

void LiveEstimator::publish_descriptions_if_changed() {
  if (descriptions_sent_ > 0 && body_file_.generation() == descriptions_generation_) return;
  descriptions_generation_ = body_file_.generation();
  const msg::BodyDescriptions message = to_descriptions_message(
      tracker_.body_definitions(), ++descriptions_sent_, body_file_.path(), wall_now_ns(),
      session_.inside_out().rig_descriptions(),
      options_.segments ? options_.segments->descriptions() : std::vector<BodyDefinition>{});
  segment_ids_.clear();
  for (const auto& description : message.bodies()) {
    if (description.kind() == "segment") segment_ids_.emplace(description.name(), description.id());
  }
  descriptions_writer_->write(message);
}

void LiveEstimator::name_markers(session::FrameOutput& output) const {
  if (!options_.labels) return;
  for (auto& marker : output.markers) {
    if (const auto label = options_.labels->label_of(marker.track.id)) {
      marker.subject = label->subject;
      marker.name = label->marker;
    }
  }
  if (options_.segments) options_.segments->append(output, segment_ids_);
}

void LiveEstimator::publish_labels_if_changed() {
  if (!labels_writer_ || options_.labels->map()->generation == labels_generation_) return;
  const msg::MarkerLabels message = to_labels_message(*options_.labels);
  labels_generation_ = message.generation();
  labels_writer_->write(message);
}

void LiveEstimator::finish(Processed& done) {
  msg::TrackFrame message;
  message.stamp_ns(done.frame.stamp_ns);
  message.source_camera(done.frame.camera_id);
  message.source_frame(done.frame.frame);
  for (const auto& track : done.tracks) message.tracks().push_back(dds::to_message(track));
  message.publish_ns(wall_now_ns());
  track_writer_->write(message);
  publish_predictions(done.frame);
  if (ros2_ && !frame_clock_) ros2_->publish(done.output);
  outputs_->write_tracks(done.tracks);
  outputs_->write_poses(done.poses);
  if (latency_probe_) latency_probe_->trace(done.frame, done.stamps, message.publish_ns());
}

// Finishes processed frames while no other frame is due and no fixed-rate instant falls due
// before one more would be finished (all of them with `force`). True when all are finished.
bool LiveEstimator::finish_processed(bool force) {
  phase_ = kFinishing;
  // Behind for long (a frame always due), they are finished anyway once the oldest has waited
  // kFinishOverdueNs, and the loop's chores follow: their tracks, the cameras' predictions and
  // the ROS 2 outputs, and the status, a lost camera's report and the bodies file's reload waited
  // until the estimator caught up (4-16 s on a loaded machine: a body made live was tracked 8.4 s
  // after its creation, test_body_create).
  constexpr TimeNs kFinishOverdueNs = 100'000'000;
  force = force || (finished_ < processed_.size() && wall_now_ns() - unfinished_since_ns_ > kFinishOverdueNs);
  while (finished_ < processed_.size() &&
         (force || (!session_.inbox().has_due(wall_now_ns()) && !near_instant(finish_work_.ns)))) {
    const TimeNs started = wall_now_ns();
    finish(processed_[finished_++]);
    finish_work_.add(wall_now_ns() - started);
  }
  if (finished_ < processed_.size()) return false;
  processed_.clear();
  finished_ = 0;
  return true;
}

void LiveEstimator::receive(msg::FeatureFrame&& message, const dds::SampleSource& source) {
  const TimeNs now = wall_now_ns();
  const std::string writer = source.writer();
  const auto decision = ownership_.claim(message.camera_id(), writer, now);
  if (decision.verdict == est::CameraOwnership::Verdict::kRefused) {
    session_.note_refused(message.camera_id(), decision.first_refusal);
    if (decision.first_refusal) {
      log("camera '" + message.camera_id() + "': refusing the frames of a second writer " + writer +
          ": the id belongs to writer " + decision.owner + ", which is still sending (counted as " +
          "camera_id_claimed_by_second_writer)");
    }
    return;
  }
  if (decision.verdict == est::CameraOwnership::Verdict::kHandedOver && !options_.quiet) {
    log("camera '" + message.camera_id() + "': now written by " + writer +
        " (its previous writer sent nothing for " + std::to_string(node_.camera_lost_after_s) + " s)");
  }
  auto frame = dds::from_message(message);
  frame.received_ns = now;
  session_.offer(std::move(frame), frame.received_ns, true);
}

bool LiveEstimator::refuses_info(const msg::CameraInfo& info, const dds::SampleSource& source) {
  const std::string owner = ownership_.owner(info.camera_id());
  if (owner.empty() || owner == source.writer()) return false;
  std::lock_guard<std::mutex> lock(info_mutex_);
  ++info_rejections_["camera_info_from_second_writer"];
  return true;
}

void LiveEstimator::publish_status(TimeNs now, TimeNs start) {
  est::EstimatorUsage usage = session_.usage(now, now);
  cameras_lost_ = usage.cameras_lost;
  // Samples dropped before they reached the session (docs/hostile_input.md).
  for (const auto& [reason, n] : bus_->receive_rejections()) usage.counters[reason] += n;
  {
    std::lock_guard<std::mutex> lock(info_mutex_);
    for (const auto& [reason, n] : info_rejections_) usage.counters[reason] += n;
  }
  // Fixed-rate periods passed over while the estimator was behind (docs/frames.md).
  if (frame_clock_) usage.counters["fixed_rate_periods_skipped"] = frame_clock_->skipped();
  const double cpu_s = process_cpu_seconds();
  if (const double period_s = ns_to_seconds(now - last_status_.wall_ns);
      last_status_.wall_ns != 0 && period_s > 0) {
    usage.replays_per_s = static_cast<double>(usage.replays - last_status_.replays) / period_s;
    usage.replayed_frames_per_s =
        static_cast<double>(usage.replayed_frames - last_status_.replayed_frames) / period_s;
    usage.cpu_percent = 100.0 * (cpu_s - last_status_.cpu_s) / period_s;
  }
  last_status_ = {now, usage.replays, usage.replayed_frames, cpu_s};
  status_writer_->write(to_status_message(usage));
  if (options_.quiet) return;
  StatusLineExtras extras;
  extras.elapsed_ns = now - start;
  extras.bodies = tracker_.body_count();
  if (extras.bodies > 0) extras.bodies_tracked = tracker_.current_poses().size();
  extras.time_sync_answered = time_service_.answered();
  log(status_line(usage, extras));
}

// The calibration file changed by someone else while tracking: `estimator_node calibrate revert`
// (or accept, which leaves the cameras as they are), a new solve written onto it, a hand edit. Its
// fixed cameras that differ from those in use replace them in the tracker (their calibration
// monitoring starts again) and the calibration in use is published; a file that cannot be read is
// reported once and the calibration in use kept.
void LiveEstimator::reload_calibration_if_changed() {
  if (options_.calibration_file.empty()) return;
  const auto time = file_time(options_.calibration_file);
  if (!time || time == calibration_file_time_) return;
  calibration_file_time_ = time;
  SystemCalibration file;
  try {
    file = load_calibration(options_.calibration_file);
  } catch (const std::exception& e) {
    log(std::string("calibration: the file changed but cannot be used (keeping the calibration in use): ") +
        e.what());
    return;
  }
  std::string applied;
  for (const auto& camera : file.cameras) {
    if (camera.moving || !camera.T_world_cam) continue;  // rig mounts and unposed cameras: read at start only
    auto in_use = std::find_if(in_use_.cameras.begin(), in_use_.cameras.end(),
                               [&camera](const CameraCalibration& c) { return c.id == camera.id; });
    SystemCalibration before, after;
    if (in_use != in_use_.cameras.end()) before.cameras.push_back(*in_use);
    after.cameras.push_back(camera);
    if (changed_cameras(before, after).empty()) continue;
    tracker_.replace_camera(camera);
    if (in_use != in_use_.cameras.end()) {
      *in_use = camera;
    } else {
      in_use_.cameras.push_back(camera);
      from_file_.insert(camera.id);
    }
    applied += (applied.empty() ? "" : ", ") + camera.id;
  }
  if (applied.empty()) return;
  std::string version;
  try {
    const auto versions = CalibrationHistory(options_.calibration_file).versions();
    if (!versions.empty())
      version =
          " (version " + std::to_string(versions.back().version) + ": " + versions.back().change.reason + ")";
  } catch (const std::exception&) {  // a damaged history does not stop the file's use
  }
  log("calibration: " + options_.calibration_file + " changed" + version + ": " + applied +
      " now as in the file");
  publish_calibration();
}

void LiveEstimator::expire_idle_tracks(TimeNs now) {
  // The tracker's time only moves with frames; without this, the last tracks stayed confirmed in
  // the status and the console for as long as the estimator ran (issue 32). The wall time since
  // the last frame is added to the newest stamp, so camera clocks need not match this one. A frame
  // up to the rewind horizon late is still applied, so a pause in delivery that short (a loaded
  // machine, a camera node starved for a moment) must not delete tracks the late frames keep alive:
  // they would come back under new ids (issue 32). A longer stall (0.9 s under test_hostile's
  // attack) removes them, but the tracker keeps the confirmed ones aside for 3 s (expire()).
  const auto& tracker = session_.config().tracker;
  const TimeNs idle_ns = now - last_frame_wall_ns_;
  if (last_frame_wall_ns_ == 0 || idle_ns <= tracker.delete_after_ns + tracker.rewind_horizon_ns) return;
  if (tracker_.live_track_count() == 0) return;
  if (const std::size_t deleted = tracker_.expire(tracker_.last_stamp_ns() + idle_ns);
      deleted > 0 && !options_.quiet)
    log("no frame for " + std::to_string(idle_ns / 1'000'000) + " ms: " + std::to_string(deleted) +
        " track(s) deleted (the confirmed ones return if frames come back within 3 s, and their markers' "
        "new tracks take their ids when the match is clear)");
}

// --realtime-priority: this thread (which fuses and publishes) under SCHED_FIFO, so that a frame's
// instant is not missed because another process holds the core (docs/frames.md). Refused without
// CAP_SYS_NICE: said once, and the thread stays under the normal scheduler.
void LiveEstimator::use_realtime_priority() {
  if (node_.realtime_priority <= 0) return;
  sched_param param{};
  param.sched_priority = node_.realtime_priority;
  const int error = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  if (error == 0) {
    if (!options_.quiet)
      log("estimator thread at SCHED_FIFO priority " + std::to_string(node_.realtime_priority));
    return;
  }
  log("warning: --realtime-priority " + std::to_string(node_.realtime_priority) + ": " +
      std::strerror(error) +
      (error == EPERM ? " (needs root or CAP_SYS_NICE: setcap cap_sys_nice+ep estimator_node)" : "") +
      "; the normal scheduler is used");
}

// The loop's periodic work between frames: the latency probe, the bodies file, descriptions, idle
// tracks and the status.
void LiveEstimator::do_chores(Chores& chores, TimeNs now, TimeNs start) {
  phase_ = kHousekeeping;
  if (latency_probe_) latency_probe_->flush(now, false);
  if (now >= chores.next_body_poll) {
    chores.next_body_poll = now + seconds_to_ns(node_.bodies_poll_s);
    body_file_.reload_if_changed(tracker_);
    reload_calibration_if_changed();
  }
  publish_descriptions_if_changed();
  expire_idle_tracks(now);
  constexpr TimeNs kHealthCheckNs = 50'000'000;
  if (now >= chores.next_status) {
    chores.next_status += seconds_to_ns(node_.status_period_s);
    publish_status(now, start);
  } else if (now >= chores.next_health_check) {
    // A camera lost (or back) is reported at once, not at the next period (issue 34: within 1 s).
    chores.next_health_check = now + kHealthCheckNs;
    if (session_.cameras_lost(now) != cameras_lost_) publish_status(now, start);
  }
}

int LiveEstimator::run() {
  auto& inbox = session_.inbox();
  // Fixed-rate frames wait for their instant in inbox.wait: the default 50 us timer slack of a
  // normal thread would be most of the +-2 % of a 120 Hz period they may be late (docs/frames.md).
  if (frame_clock_) prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  use_realtime_priority();
  const TimeNs start = wall_now_ns();
  last_status_ = {start, 0, 0, process_cpu_seconds()};
  Chores chores{start + seconds_to_ns(node_.status_period_s), start + seconds_to_ns(node_.bodies_poll_s),
                start};
  while (!stop_requested()) {
    apply_announced_cameras();
    publish_fixed_frame();
    const TimeNs now = wall_now_ns();
    if (auto due = inbox.pop_due(now); !due.empty()) {
      last_frame_wall_ns_ = now;
      update(due);
      publish_fixed_frame();  // an instant that fell due during the update goes out now
    }
    const bool finished = finish_processed(false);
    publish_fixed_frame();
    if (!finished) continue;  // a frame is due (its update first) or a fixed-rate instant is near
    // The chores wait until after a fixed-rate instant that falls due within 1 ms (a quarter period).
    if (!near_instant(std::min<TimeNs>(
            1'000'000, static_cast<TimeNs>(frame_clock_ ? frame_clock_->period_ns() / 4 : 0))))
      do_chores(chores, now, start);
    if (options_.duration_s > 0 && now - start >= seconds_to_ns(options_.duration_s)) break;
    phase_ = kWaiting;
    inbox.wait(wall_now_ns(), max_wait());  // wakes as frames arrive (issue 7)
  }
  if (auto rest = inbox.drain(); !rest.empty()) update(rest);
  finish_processed(true);
  if (latency_probe_) latency_probe_->flush(wall_now_ns(), true);
  session_.print_summary(0);
  if (frame_clock_) {
    log("fixed-rate frames: " + std::to_string(frame_clock_->published()) + " published, " +
        std::to_string(frame_clock_->skipped()) + " periods skipped (the estimator was behind), " +
        std::to_string(frame_clock_->idle()) + " idle (no camera sending); " + std::to_string(holds_) +
        " updates held for an instant; frames written > 2 % of a period after their instant, by what "
        "the loop was doing then: " +
        std::to_string(late_by_phase_[kWaiting]) + " waiting for frames, " +
        std::to_string(late_by_phase_[kUpdating]) + " updating, " +
        std::to_string(late_by_phase_[kFinishing]) + " finishing frames, " +
        std::to_string(late_by_phase_[kHousekeeping]) + " chores");
    log(fixed_rate_stats_.summary());
  }
  // Everything the run produced is written; what remains is closing the DDS entities, which Fast
  // DDS 2.9 can stall on (a secured participant): the process ends anyway 10 s from now.
  outputs_->flush();
  if (options_.labels) options_.labels->flush();
  if (options_.chains) options_.chains->flush();
  std::fflush(nullptr);
  end_within(std::chrono::seconds(10), kExitOk, "closing the DDS participant");
  return kExitOk;
}

}  // namespace

int run_live(const LiveOptions& options, session::EstimatorSession& session, session::BodyFile& body_file) {
  LiveEstimator live(options, session, body_file);
  return live.run();
}

}  // namespace panoptes::estimator_app
