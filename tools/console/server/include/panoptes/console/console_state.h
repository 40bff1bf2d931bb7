// SPDX-License-Identifier: Apache-2.0
// What panoptes_console knows about the bus, one model per area: cameras (camera_model.h), the
// estimator's status (estimator_model.h), its tracks, bodies and chains (scene_model.h), the
// recorders (recorder_model.h), the calibration page (calibration_model.h) and the commands
// waiting for an acknowledgement (command_model.h). DDS listener threads write it; the server
// thread reads it ~30 times a second into one JSON snapshot shared by every browser
// (docs/console.md). Plain types only: no DDS, so the server is tested without a bus.
//
// Locking (docs/console.md, "Behaviour under load"): one mutex per model, so that a camera's
// features, the estimator's tracks and a recorder's status, which arrive on different listener
// threads, never wait for each other. Each model's part of a snapshot is taken under that model's
// lock alone, and so is consistent in itself (the scene's tracks, bodies and chains are of one
// moment); parts of different models are from instants a few microseconds apart, which the page
// cannot tell from the bus's own delivery order. Only two operations hold two locks, always taken
// together with std::scoped_lock: a camera's status with the commands (the status resolves them,
// and a command sent records the counts of the status it is compared with), and a recorder's
// status with the commands.
#pragma once

#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "panoptes/console/calibration_model.h"
#include "panoptes/console/camera_model.h"
#include "panoptes/console/command_model.h"
#include "panoptes/console/console_records.h"
#include "panoptes/console/estimator_model.h"
#include "panoptes/console/recorder_model.h"
#include "panoptes/console/scene_model.h"

namespace panoptes::console {

class ConsoleState {
 public:
  explicit ConsoleState(StateOptions options = {})
      : cameras_(options), scene_(options), recorders_(options), commands_(options) {}

  void on_info(const std::string& camera, CameraInfoRecord info, TimeNs now);
  void on_status(const std::string& camera, CameraStatusRecord status, TimeNs now);
  void on_features(const std::string& camera, FeatureRecord features, TimeNs now);
  void on_predictions(const std::string& camera, std::vector<PredictedWindowRecord> windows, TimeNs now);
  // A camera's preview image (8-bit grey, row-major), as camera_node sends it on request; dropped
  // when its size does not match its pixels.
  void on_preview(const std::string& camera, TimeNs stamp_ns, int width, int height, std::string pixels);
  // The camera's latest preview as a binary PGM (P5) image; nullopt when it sent none.
  std::optional<std::string> preview_pgm(const std::string& camera) const;
  void on_calibration(const std::map<std::string, CameraGeometry>& cameras);
  void on_estimator(EstimatorRecord status, TimeNs now);
  void on_tracks(std::vector<TrackPoint> tracks, TimeNs now);
  void on_body(BodyRecord body, TimeNs now);
  void on_labels(std::vector<SubjectLabelsRecord> subjects);
  void on_recorder_status(const std::string& recorder, RecorderRecord status, TimeNs now);
  // A chain sample, kept or counted as dropped (SceneModel::on_chains; the full snapshot's
  // "chain_samples"). False when dropped.
  bool on_chains(ChainFrameRecord frame, TimeNs now);

  bool knows_camera(const std::string& camera) const;
  // Image size of a camera, if its camera_info was seen with one.
  std::optional<std::pair<int, int>> image_size(const std::string& camera) const;
  // Records a forwarded command; its outcome comes from take_outcomes().
  void on_command_sent(PendingCommand command);
  void on_recorder_command_sent(PendingRecorderCommand command);
  bool knows_recorder(const std::string& recorder) const;
  std::vector<CommandOutcome> take_outcomes(TimeNs now);
  // CommandModel::on_outcome.
  void on_outcome(CommandOutcome outcome);

  // Wand capture coverage (the calibration page, CalibrationModel), fed with the frames the
  // capture writes (the same frames the CLI counts).
  void start_coverage(TimeNs now);
  void add_coverage_frame(const std::string& camera, const std::vector<BlobPoint>& blobs);
  void stop_coverage();
  void set_calibration_job(std::string summary_json, std::string full_json);
  std::string calibration_job() const;

  // The figures of one track, body or chain for the page's details panel (SceneModel::details).
  nlohmann::json details(const std::string& kind, const std::string& key, TimeNs now) const;

  // The state as JSON (docs/console.md, "Protocol"): each model's to_json, the slow parts (camera
  // info, geometry, status and usage; the estimator; recorders; calibration; chain sample counts)
  // only when `full`.
  nlohmann::json snapshot(TimeNs now, bool full) const;

 private:
  // A model and the mutex that guards it.
  template <class Model>
  struct Guarded {
    template <class... Args>
    explicit Guarded(Args&&... args) : model(std::forward<Args>(args)...) {}
    mutable std::mutex mutex;
    Model model;
  };

  Guarded<CameraModel> cameras_;
  Guarded<EstimatorModel> estimator_;
  Guarded<SceneModel> scene_;
  Guarded<RecorderModel> recorders_;
  Guarded<CalibrationModel> calibration_;
  Guarded<CommandModel> commands_;
};

}  // namespace panoptes::console
