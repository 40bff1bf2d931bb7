// SPDX-License-Identifier: Apache-2.0
#include "panoptes/session/offline_replay.h"

#include <algorithm>
#include <cstdio>
#include <iterator>
#include <numeric>
#include <tuple>

#include "panoptes/process.h"
#include "panoptes/session/frame_clock.h"
#include "panoptes/session/log.h"

namespace panoptes::session {

namespace est = panoptes::estimator;

FeatureFiles read_feature_files(const std::vector<std::string>& paths) {
  FeatureFiles files;
  for (const auto& path : paths) {
    std::vector<std::string> errors;
    std::vector<FeatureFrame> part = read_feature_frames(path, &errors);
    for (std::size_t i = 0; i < errors.size() && i < 5; ++i) log("skipped " + errors[i]);
    if (errors.size() > 5) log("... and " + std::to_string(errors.size() - 5) + " more malformed lines");
    files.bad_lines += errors.size();
    files.frames.insert(files.frames.end(), std::make_move_iterator(part.begin()),
                        std::make_move_iterator(part.end()));
  }
  return files;
}

void sort_by_stamp(std::vector<FeatureFrame>& frames) {
  std::stable_sort(frames.begin(), frames.end(), [](const auto& a, const auto& b) {
    return std::tie(a.stamp_ns, a.camera_id, a.frame) < std::tie(b.stamp_ns, b.camera_id, b.frame);
  });
}

std::vector<std::size_t> delivery_order(const std::vector<FeatureFrame>& frames, bool by_arrival) {
  std::vector<std::size_t> order(frames.size());
  std::iota(order.begin(), order.end(), 0);
  if (!by_arrival) return order;
  const auto received = [&](std::size_t i) {
    return frames[i].received_ns != 0 ? frames[i].received_ns : frames[i].stamp_ns;
  };
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return received(a) < received(b); });
  return order;
}

void replay_frames(EstimatorSession& session, std::vector<FeatureFrame>& frames,
                   const OfflineReplayOptions& options, const DeliveredFrame& delivered) {
  // Offline there is no wall clock: each stamp is judged against its neighbours'.
  const auto references = est::offline_reference_stamps(frames);
  const auto order = delivery_order(frames, options.by_arrival);
  const auto deliver = [&](const FeatureFrame& frame) { delivered(frame, session.process(frame)); };
  const std::function<void(FeatureFrame&, est::FrameOutcome)> deliver_due = delivered;
  auto& inbox = session.inbox();
  const std::size_t progress_every = std::max<std::size_t>(frames.size() / 10, 1);
  for (std::size_t n = 0; n < order.size(); ++n) {
    const std::size_t i = order[n];
    FeatureFrame& frame = frames[i];
    if (options.by_arrival && frame.received_ns == 0) frame.received_ns = frame.stamp_ns;
    if (options.clock) options.clock(options.by_arrival ? frame.received_ns : frame.stamp_ns);
    if (session.admit(frame, references[i], false)) {
      if (options.by_arrival) {
        const TimeNs now = frame.received_ns;
        inbox.push(std::move(frame));
        auto due = inbox.pop_due(now);
        session.process_due(due, deliver_due);
      } else {
        deliver(frame);
      }
    }
    if (options.show_progress && (n + 1) % progress_every == 0) {
      std::fprintf(stderr, "\restimator_node: %3zu%% (%zu/%zu frames, %zu live tracks)",
                   (n + 1) * 100 / frames.size(), n + 1, frames.size(), session.tracker().live_track_count());
    }
  }
  auto rest = inbox.drain();
  session.process_due(rest, deliver_due);
  if (options.show_progress && !frames.empty()) std::fprintf(stderr, "\n");
}

int run_offline(EstimatorSession& session, const std::vector<std::string>& feature_files,
                const OfflineReplayOptions& options, const std::string& out_tracks,
                const std::string& out_poses) {
  FeatureFiles input;
  try {
    input = read_feature_files(feature_files);
  } catch (const std::exception& error) {
    log(error.what());
    return kExitBadInput;
  }
  return run_offline(session, std::move(input), options, out_tracks, out_poses);
}

int run_offline(EstimatorSession& session, FeatureFiles input, const OfflineReplayOptions& options,
                const std::string& out_tracks, const std::string& out_poses) {
  sort_by_stamp(input.frames);
  JsonlOutputs outputs(out_tracks, out_poses);
  const est::Tracker& tracker = session.tracker();
  const bool fixed = session.config().node.fixed_rate_offline();
  FrameClock clock(session.config().node.frame_rate_hz);
  FixedRateStats stats;
  OfflineReplayOptions replay = options;
  if (fixed) {
    // Instants strictly before the clock: a frame stamped at an instant is processed first.
    replay.clock = [&](TimeNs now) {
      if (tracker.last_stamp_ns() == 0) return;  // nothing to predict from yet
      while (const auto tick = clock.next_due(now - 1)) {
        stats.add(tick->instant_ns - tracker.last_stamp_ns());
        if (outputs.writes_tracks()) outputs.write_tracks(tracker.tracks_at(tick->instant_ns));
        if (outputs.writes_poses()) outputs.write_poses(session.poses_at(tick->instant_ns));
      }
    };
  }
  replay_frames(session, input.frames, replay, [&](const FeatureFrame& frame, est::FrameOutcome outcome) {
    // Tracks and poses are written when the newest stamp advances; a replayed late frame refines
    // the state that the next frame's output shows.
    if (outcome != est::FrameOutcome::kProcessed) return;
    if (options.chains) options.chains->observe(frame, tracker);
    if (options.labels) options.labels->observe(tracker);
    if (fixed) return;
    if (outputs.writes_tracks()) outputs.write_tracks(tracker.current_tracks());
    if (outputs.writes_poses()) outputs.write_poses(session.current_poses());
  });
  session.print_summary(input.bad_lines);
  if (fixed) log(stats.summary());
  if (options.chains) {
    options.chains->flush();
    log(options.chains->summary());
  }
  if (options.labels) {
    options.labels->flush();
    log(options.labels->summary());
  }
  log(outputs.summary());
  return kExitOk;
}

}  // namespace panoptes::session
