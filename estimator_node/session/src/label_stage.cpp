// SPDX-License-Identifier: Apache-2.0
#include "panoptes/session/label_stage.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <thread>
#include <utility>

#include <nlohmann/json.hpp>

#include "panoptes/labelling_files/subject_model_file.h"

namespace panoptes::session {

namespace {

std::vector<std::string> subject_names(const std::vector<labelling::SubjectModel>& models) {
  std::vector<std::string> names;
  names.reserve(models.size());
  for (const auto& model : models) names.push_back(model.subject);
  return names;
}

}  // namespace

struct LabelStage::Core {
  Core(std::vector<labelling::SubjectModel> models, const labelling::LabellerOptions& options)
      : subjects(subject_names(models)), labeller(std::move(models), options) {}

  // One labeller run on `points` at `stamp`; publishes a new map when the names changed.
  void run(const std::vector<labelling::TrackPoint>& points, TimeNs stamp) {
    const auto start = std::chrono::steady_clock::now();
    labeller.update(points, static_cast<double>(stamp) * 1e-9);
    const double us =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
    const double per_subject = us / static_cast<double>(std::max<std::size_t>(subjects.size(), 1));
    std::vector<TrackLabel> names;
    for (const auto& [track, label] : labeller.labels())
      names.push_back({static_cast<std::int64_t>(track), subjects.at(label.subject), label.marker});
    const auto same = [](const TrackLabel& a, const TrackLabel& b) {
      return a.track == b.track && a.subject == b.subject && a.marker == b.marker;
    };
    std::lock_guard<std::mutex> lock(mutex);
    total_us += per_subject;
    worst_us = std::max(worst_us, per_subject);
    ++runs;
    ran_stamp = stamp;
    untangled = labeller.untangled();
    released = labeller.released();
    if (map->generation != 0 &&
        std::equal(names.begin(), names.end(), map->labels.begin(), map->labels.end(), same))
      return;
    map = std::make_shared<const LabelMap>(LabelMap{std::move(names), map->generation + 1, stamp});
  }

  void work() {
    std::unique_lock<std::mutex> lock(mutex);
    for (;;) {
      wake.wait(lock, [this] { return stop || job_stamp != 0; });
      if (stop) return;
      std::vector<labelling::TrackPoint> points = std::move(job);
      const TimeNs stamp = std::exchange(job_stamp, 0);
      busy = true;
      lock.unlock();
      run(points, stamp);
      lock.lock();
      busy = false;
      idle.notify_all();
    }
  }

  // The newest map into `names`; returns the stamp of the run that made it (0: none yet).
  TimeNs newest(std::shared_ptr<const LabelMap>& names) const {
    std::lock_guard<std::mutex> lock(mutex);
    names = map;
    return ran_stamp;
  }

  void drain() {
    std::unique_lock<std::mutex> lock(mutex);
    idle.wait(lock, [this] { return stop || (job_stamp == 0 && !busy); });
  }

  void post(const std::vector<labelling::TrackPoint>& points, TimeNs stamp) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      job = points;  // a job not started yet is replaced by the newer tracks
      job_stamp = stamp;
    }
    wake.notify_one();
  }

  ~Core() {
    if (!worker.joinable()) return;
    {
      std::lock_guard<std::mutex> lock(mutex);
      stop = true;
    }
    wake.notify_one();
    worker.join();
  }

  const std::vector<std::string> subjects;  // before labeller: built from the models it takes
  labelling::Labeller labeller;             // run() only: the worker's alone once it runs
  mutable std::mutex mutex;                 // guards what follows
  std::shared_ptr<const LabelMap> map = std::make_shared<const LabelMap>();
  std::uint64_t runs = 0;
  TimeNs ran_stamp = 0;         // the newest finished run's stamp
  std::uint64_t untangled = 0;  // labeller.untangled() after the newest run
  std::uint64_t released = 0;   // labeller.released() after the newest run
  double total_us = 0.0;
  double worst_us = 0.0;
  std::condition_variable wake;
  std::vector<labelling::TrackPoint> job;
  TimeNs job_stamp = 0;  // 0: no job waiting
  bool busy = false;     // a run is under way
  bool stop = false;
  std::condition_variable idle;  // after each run in the background
  std::thread worker;            // last: started after everything above exists
};

LabelStage::LabelStage(std::vector<labelling::SubjectModel> models, const labelling::LabellerOptions& options,
                       const std::string& out_path, TimeNs period_ns)
    : core_(std::make_unique<Core>(std::move(models), options)),
      period_ns_(period_ns),
      max_lag_ns_(std::max<TimeNs>(4 * period_ns, 20'000'000)) {
  if (!out_path.empty()) out_.emplace(out_path);
}

LabelStage::~LabelStage() = default;
LabelStage::LabelStage(LabelStage&&) noexcept = default;
LabelStage& LabelStage::operator=(LabelStage&&) noexcept = default;

LabelStage LabelStage::from_files(const std::vector<std::string>& subject_files,
                                  const labelling::LabellerOptions& options, const std::string& out_path,
                                  TimeNs period_ns) {
  std::vector<labelling::SubjectModel> models;
  models.reserve(subject_files.size());
  for (const auto& path : subject_files) models.push_back(labelling::load_subject_model(path));
  return LabelStage(std::move(models), options, out_path, period_ns);
}

void LabelStage::run_in_background() {
  if (!core_->worker.joinable()) core_->worker = std::thread([core = core_.get()] { core->work(); });
}

void LabelStage::drain() {
  if (core_->worker.joinable()) core_->drain();
}

std::shared_ptr<const LabelMap> LabelStage::map() const {
  std::lock_guard<std::mutex> lock(core_->mutex);
  return core_->map;
}

const labelling::SubjectModel& LabelStage::model(std::size_t subject) const {
  return core_->labeller.model(subject);  // the models never change: safe beside a run
}

std::size_t LabelStage::subject_count() const {
  return core_->subjects.size();
}

void LabelStage::observe(const estimator::Tracker& tracker) {
  const TimeNs stamp = tracker.last_stamp_ns();
  if (stamp <= last_stamp_ns_) return;
  const bool due = last_run_ns_ == 0 || stamp - last_run_ns_ >= period_ns_;
  // On the frame path only what is needed: the tracks when the labeller runs or --out-labels
  // writes them, and the newest map for label_of().
  observe(tracker, due || out_ ? tracker.current_tracks() : std::vector<TrackRecord>{});
}

void LabelStage::observe(const estimator::Tracker& tracker, const std::vector<TrackRecord>& current_tracks) {
  const TimeNs stamp = tracker.last_stamp_ns();
  if (stamp <= last_stamp_ns_) return;  // nothing new (a late frame refined an older instant)
  last_stamp_ns_ = stamp;
  const bool due = last_run_ns_ == 0 || stamp - last_run_ns_ >= period_ns_;
  if (due || out_) {
    points_.clear();
    for (const auto& track : current_tracks) {
      if (track.status != TrackStatus::kConfirmed) continue;
      points_.push_back({static_cast<std::uint64_t>(track.id), track.p});
    }
  }
  if (due) {
    last_run_ns_ = stamp;
    if (core_->worker.joinable()) {
      core_->post(points_, stamp);
    } else {
      core_->run(points_, stamp);
    }
  }
  // The run whose names this frame carries (--out-labels: a live run's lag).
  TimeNs labelled_ns = core_->newest(names_);
  // Names at most max_lag_ns behind the frame (header): else this frame waits for the run just
  // posted, which the wait itself lets the worker have the CPU for (the first run too).
  if (due && core_->worker.joinable() && stamp - labelled_ns > max_lag_ns_) {
    core_->drain();
    ++waits_;
    labelled_ns = core_->newest(names_);
  }
  if (due) {  // the share named, counted at the labeller's runs (every frame offline by default)
    marker_frames_ += points_.size();
    for (const auto& point : points_)
      labelled_marker_frames_ += label_of(static_cast<std::int64_t>(point.track)) ? 1 : 0;
  }
  if (!out_) return;
  // Every confirmed track with its position; "subject"/"marker" only on the labelled ones;
  // "labelled_ns": the stamp of the labeller run whose names these are (live: behind "stamp_ns" by
  // the run period and the worker's lag; panoptes_label_replay --as-recorded replays that schedule).
  nlohmann::json record{
      {"stamp_ns", stamp}, {"labelled_ns", labelled_ns}, {"tracks", nlohmann::json::array()}};
  for (const auto& point : points_) {
    nlohmann::json entry{{"track", static_cast<std::int64_t>(point.track)},
                         {"p", {point.position_m.x(), point.position_m.y(), point.position_m.z()}}};
    if (const TrackLabel* label = find(static_cast<std::int64_t>(point.track))) {
      entry["subject"] = label->subject;
      entry["marker"] = label->marker;
    }
    record["tracks"].push_back(std::move(entry));
  }
  out_->write_line(record.dump());
}

const TrackLabel* LabelStage::find(std::int64_t track) const {
  if (!names_) return nullptr;
  const auto found =
      std::lower_bound(names_->labels.begin(), names_->labels.end(), track,
                       [](const TrackLabel& label, std::int64_t id) { return label.track < id; });
  return found != names_->labels.end() && found->track == track ? &*found : nullptr;
}

std::optional<TrackLabel> LabelStage::label_of(std::int64_t track) const {
  const TrackLabel* label = find(track);
  if (label == nullptr) return std::nullopt;
  return *label;
}

std::string LabelStage::summary() const {
  const double named = marker_frames_ == 0 ? 0.0
                                           : 100.0 * static_cast<double>(labelled_marker_frames_) /
                                                 static_cast<double>(marker_frames_);
  std::uint64_t runs = 0;
  std::uint64_t untangled = 0;
  std::uint64_t released = 0;
  double total_us = 0.0;
  double worst_us = 0.0;
  {
    std::lock_guard<std::mutex> lock(core_->mutex);
    runs = core_->runs;
    untangled = core_->untangled;
    released = core_->released;
    total_us = core_->total_us;
    worst_us = core_->worst_us;
  }
  const double mean = runs == 0 ? 0.0 : total_us / static_cast<double>(runs);
  char text[560];
  std::snprintf(text, sizeof text,
                "labels: %zu subject%s, %.2f %% of %llu confirmed marker-frames at the labeller's runs "
                "named, %.1f us per subject-frame (mean; worst %.0f us) over %llu runs%s; %llu pairs of "
                "names untangled, %llu names released from tracks that stopped fitting; %llu frames waited "
                "for a run (names over %.0f ms behind)",
                core_->subjects.size(), core_->subjects.size() == 1 ? "" : "s", named,
                static_cast<unsigned long long>(marker_frames_), mean, worst_us,
                static_cast<unsigned long long>(runs), core_->worker.joinable() ? " (in the background)" : "",
                static_cast<unsigned long long>(untangled), static_cast<unsigned long long>(released),
                static_cast<unsigned long long>(waits_), static_cast<double>(max_lag_ns()) * 1e-6);
  return text;
}

}  // namespace panoptes::session
