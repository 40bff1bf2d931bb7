// SPDX-License-Identifier: Apache-2.0
// Panoptes client library: the one way applications read Panoptes (docs/clients.md).
//
//   panoptes::client::Client client;                    // loopback profile, $PANOPTES_DOMAIN
//   auto result = client.wait_for_frame(std::chrono::seconds(2));
//   if (result.status == panoptes::client::Status::kOk)
//     for (const auto& body : result.frame.bodies) ...
//
// No DDS and no generated types in this header: it depends on the C++ standard library only.
// Errors: the constructor throws ClientError (the bus cannot be opened), OptionError when an
// option, $PANOPTES_DOMAIN or the DDS profile is invalid; body_description() throws
// UnknownBody. Nothing else throws: other failures are reported
// in Status and Stats. Every member function is thread-safe.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

// Only what this header declares is exported from libpanoptes_client.so (built with hidden
// visibility and a version script).
#if defined(__GNUC__)
#define PANOPTES_CLIENT_API __attribute__((visibility("default")))
#else
#define PANOPTES_CLIENT_API
#endif

namespace panoptes::client {

using Vec3 = std::array<double, 3>;
using Quat = std::array<double, 4>;  // x, y, z, w

class PANOPTES_CLIENT_API ClientError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// An invalid option, an invalid $PANOPTES_DOMAIN (not an integer 0..232), a DDS profile or DDS
// Security file that is missing or cannot be used: found before any participant exists; what()
// names the option, variable or file ("PANOPTES_DOMAIN=abc: not a DDS domain id (an integer
// 0..232)", "panoptes client: DDS profile x.xml: no such file"). A usage error: the Panoptes
// programs exit 2 on it.
class PANOPTES_CLIENT_API OptionError : public ClientError {
 public:
  using ClientError::ClientError;
};

// A body name that no BodyDescription carries; what() names it.
class PANOPTES_CLIENT_API UnknownBody : public ClientError {
 public:
  using ClientError::ClientError;
};

struct ClientOptions {
  std::string profile_file;  // DDS XML profile; empty: $PANOPTES_DDS_PROFILE, else the loopback profile
  int domain_id = -1;        // 0..232; -1: $PANOPTES_DOMAIN, else 0
  // A frame older than this (by arrival) makes the client "stale"; status_text() says since when.
  std::chrono::milliseconds stale_after{1000};
  // Frames kept for wait_for_frame() (>= 1). When it is full the oldest is dropped; drops are counted
  // once wait_for_frame() has been called (before that the queue only remembers the latest frames,
  // so an application that reads by callback or latest() alone sees no drops).
  std::size_t queue_depth = 1024;
  bool reliable = true;  // ask the estimator to repair lost frames (no drops on a busy host)
  // The world's up axis in everything this client returns (docs/clients.md, "Axis conventions"):
  // "z" (Panoptes' world, as published) or "y" (y up: (x, y, z) -> (x, z, -y), orientations turned
  // with it, body layouts unchanged). Empty: $PANOPTES_UP_AXIS, else "z". Anything else: OptionError.
  std::string up_axis;
};

// A point track (a 3D marker) with its label. Labelled markers are the markers of tracked rigid
// bodies (body, body_marker); unlabelled ones are loose markers. Both keep a stable id while tracked.
struct Marker {
  std::int64_t id = 0;
  Vec3 position{};                     // m, world
  Vec3 velocity{};                     // m/s
  std::array<double, 6> covariance{};  // position covariance, m²: xx xy xz yy yz zz
  int cameras = 0;                     // cameras that updated it recently
  bool occluded = false;               // coasting: no camera saw it lately, position predicted
  std::string body;                    // "": unlabelled
  int body_marker = -1;                // index in the body's marker layout
  bool labelled() const { return !body.empty(); }
  // Its marker-set name when the estimator labels subjects (--subjects; rt/panoptes/labels,
  // docs/marker_sets.md): subject "s1", name "R.ASIS"; both "" when unnamed.
  std::string subject;
  std::string name;
  bool named() const { return !name.empty(); }
};

struct RigidBody {
  std::string name;
  int id = 0;  // 1-based position in the bodies file
  bool tracking_valid = false;
  Vec3 position{};                         // m, world
  Quat orientation{0, 0, 0, 1};            // x, y, z, w: body frame -> world
  Vec3 linear_velocity{};                  // m/s, world
  Vec3 angular_velocity{};                 // rad/s, world
  std::array<double, 6> sigma{};           // 1-σ: x, y, z (m), rotation about x, y, z (rad)
  double quality = 0.0;                    // fraction of its markers seen recently, 0..1
  double mean_marker_error = 0.0;          // m, labelled markers against the layout
  std::int64_t prediction_horizon_ns = 0;  // the pose is predicted this far past the frame's stamp
  int cameras = 0;
};

// Latency of a frame, ns. Stages measured on different hosts are on the common time base (camera
// nodes synchronise their clocks to the estimator's); 0 means unknown.
struct Latency {
  std::int64_t capture_to_publish_ns = 0;  // mid-exposure -> the estimator wrote the frame
  std::int64_t publish_to_receive_ns = 0;  // the estimator wrote it -> this client received it
  std::int64_t capture_to_receive_ns = 0;  // the total an application sees
  // Per stage (0 if unknown):
  std::int64_t camera_ns = 0;   // mid-exposure -> camera_node published the 2D features
  std::int64_t network_ns = 0;  // camera_node published -> estimator_node received
  std::int64_t queue_ns = 0;    // waiting in the estimator's inbox (its latency window)
  std::int64_t update_ns = 0;   // the filter update
  std::int64_t output_ns = 0;   // the update -> the frame was written
};

struct Frame;

// The named markers of one subject in one frame: frame.subject("s1").marker("R.ASIS"). Refers to
// the frame it came from (valid while that frame lives).
struct PANOPTES_CLIENT_API SubjectMarkers {
  const Frame* frame = nullptr;
  std::string subject;
  // nullptr if no marker of this subject carries that name in the frame (hidden, or not named yet).
  const Marker* marker(const std::string& name) const;
  std::vector<const Marker*> markers() const;  // every marker of the subject named in the frame
};

struct PANOPTES_CLIENT_API Frame {
  std::uint64_t frame_number = 0;  // from 1 in each estimator run (restarts begin again at 1)
  std::int64_t stamp_ns = 0;       // mid-exposure capture time, common clock
  std::int64_t publish_ns = 0;     // the estimator wrote it
  std::int64_t receive_ns = 0;     // this client received it (its system clock)
  std::string source_camera;       // camera whose frame produced this update
  std::int64_t source_frame = 0;
  Latency latency;
  std::vector<RigidBody> bodies;  // every defined body, tracked or not
  std::vector<Marker> markers;    // labelled and unlabelled
  std::vector<Vec3> unlabelled_markers() const;
  // nullptr if no body of that name is in this frame.
  const RigidBody* body(const std::string& name) const;
  SubjectMarkers subject(const std::string& name) const;
};

// A subject the estimator labels (rt/panoptes/labels): its marker set's names and sticks (pairs of
// names drawn joined).
struct SubjectDescription {
  std::string name;
  std::string marker_set;
  std::vector<std::string> markers;
  std::vector<std::pair<std::string, std::string>> sticks;
};

struct BodyDescription {
  std::string name;
  int id = 0;
  std::string kind;           // passive | led7 | rig (an inside-out rig: its markers may be empty) | segment
  std::vector<Vec3> markers;  // m, body frame
};

// Surface mode (docs/surface.md): one event of a stroke on the wall (rt/panoptes/strokes).
enum class StrokePhase {
  kBegin,     // a new stroke: stamp and position of its first spot
  kContinue,  // the filtered state at an update
  kEnd,       // the stroke ended: stamp and state of its last update
};

struct Stroke {
  StrokePhase phase = StrokePhase::kContinue;
  std::uint32_t id = 0;                  // stable for the stroke's life, from 1 in each estimator run
  std::int64_t stamp_ns = 0;             // common clock
  std::array<double, 2> position{};      // m, surface frame (s along the width, t along the height)
  std::array<double, 2> velocity{};      // m/s
  std::array<double, 2> acceleration{};  // m/s²
  int cameras = 0;                       // cameras that saw it recently
  std::array<double, 2> surface_size{};  // m, the surface's extent
  std::string source_camera;             // camera whose frame caused the event ("": the clock)
  std::int64_t publish_ns = 0;           // the estimator wrote it (common clock)
  std::int64_t receive_ns = 0;           // this client received it (its system clock)
};

// Articulated chains (docs/articulated.md): a finger's markers on a kinematic chain, from
// rt/panoptes/chains after every camera frame.
enum class ChainStatus {
  kTracking,       // angles, markers and tips hold the estimate
  kAmbiguous,      // more than one candidate: not forced onto markers, nothing estimated
  kNotIdentified,  // not found (yet, or lost)
};

struct Chain {
  std::string name;
  int id = 0;  // 1-based position among the chains of the bodies file
  ChainStatus status = ChainStatus::kNotIdentified;
  std::int64_t stamp_ns = 0;         // common clock
  std::vector<double> joint_angles;  // rad, one per joint, base first
  std::vector<Vec3> markers;         // m, world, base first
  std::vector<bool> marker_valid;    // per marker: seen within the last 50 ms
  Vec3 tip{};                        // m, world: the hot spot
  Vec3 predicted_tip{};              // m, world: prediction_horizon_ns ahead (= tip when 0)
  std::int64_t prediction_horizon_ns = 0;
  bool grabbing = false;  // between a grab and its release
  bool tracking() const { return status == ChainStatus::kTracking; }
};

enum class GrabKind {
  kGrab,     // the finger bent past the grab threshold
  kRelease,  // it straightened past the release threshold
};

// A grab gesture (seed 000 §6.4.5), delivered once.
struct GrabEvent {
  GrabKind kind = GrabKind::kGrab;
  std::string chain;
  int chain_id = 0;
  std::int64_t stamp_ns = 0;    // when the bend crossed the threshold (common clock)
  Vec3 tip{};                   // m, world, at that time
  double bend = 0.0;            // rad, the sum of the joint angles
  std::int64_t publish_ns = 0;  // the estimator wrote it (common clock)
  std::int64_t receive_ns = 0;  // this client received it (its system clock)
};

// Every chain after one camera frame, and the grab events that frame caused.
struct PANOPTES_CLIENT_API ChainUpdate {
  std::int64_t stamp_ns = 0;  // the camera frame's (mid-exposure, common clock)
  std::int64_t publish_ns = 0;
  std::int64_t receive_ns = 0;
  std::string source_camera;
  std::int64_t source_frame = 0;
  std::vector<Chain> chains;
  std::vector<GrabEvent> events;
  // nullptr if no chain of that name is in this update.
  const Chain* chain(const std::string& name) const;
};

enum class Status {
  kOk,       // what was waited for (a frame, a stroke, a grab event, the body descriptions)
  kTimeout,  // nothing within the timeout (see status_text())
  kClosed,   // close() was called
};

struct FrameResult {
  Status status = Status::kTimeout;
  Frame frame;  // empty unless kOk
};

struct DescriptionsResult {
  Status status = Status::kTimeout;
  std::vector<BodyDescription> descriptions;  // empty unless kOk (kOk and empty: no bodies defined)
};

struct StrokeResult {
  Status status = Status::kTimeout;
  Stroke stroke;  // empty unless kOk
};

struct GrabResult {
  Status status = Status::kTimeout;
  GrabEvent event;  // empty unless kOk
};

struct Stats {
  std::uint64_t frames_received = 0;
  std::uint64_t frames_dropped = 0;    // overflowed the queue
  std::uint64_t frames_missed = 0;     // gaps in frame_number: not delivered by the bus
  std::uint64_t frames_malformed = 0;  // counted and ignored
  std::uint64_t descriptions_received = 0;
  std::uint64_t descriptions_malformed = 0;   // counted and ignored
  std::uint64_t estimator_restarts = 0;       // frame_number went back: a new estimator run
  std::uint64_t callback_errors = 0;          // exceptions thrown by callbacks (caught)
  std::uint64_t strokes_received = 0;         // stroke events (surface mode)
  std::uint64_t strokes_malformed = 0;        // counted and ignored
  std::uint64_t strokes_dropped = 0;          // overflowed the stroke queue
  std::uint64_t chain_updates_received = 0;   // rt/panoptes/chains samples (articulated chains)
  std::uint64_t chain_updates_malformed = 0;  // counted and ignored
  std::uint64_t grab_events_received = 0;
  std::uint64_t grab_events_dropped = 0;  // overflowed the grab event queue
  std::uint64_t labels_received = 0;      // rt/panoptes/labels maps (names of subjects' markers)
  std::uint64_t labels_malformed = 0;     // counted and ignored
  std::string last_error;  // why the last malformed sample was ignored, or the last callback's exception
};

// The estimator's frame rate as its frames' stamps show it (docs/frames.md). With
// `estimator_node --frames fixed` the frames lie on a uniform grid of instants and `hz` is that
// grid's rate (the median interval of the last 64 frames' stamps, exact to their nanoseconds);
// with one frame per processed camera frame it is the mean rate of those frames.
struct FrameRate {
  bool fixed = false;  // the newest frame was a fixed-rate frame (no source camera)
  double hz = 0.0;     // 0 before two frames arrived
};

// A fixed-rate frame's SMPTE-style timecode (docs/frames.md, "Timecode"): hours:minutes:seconds:
// frames of the capture clock's day (UTC), frames counting 0 .. rate_hz - 1 within each second.
struct Timecode {
  int hours = 0, minutes = 0, seconds = 0, frames = 0;
  int rate_hz = 0;
  std::string text;  // "14:03:27:118"
};

// One camera as the estimator sees it (rt/panoptes/estimator_status; docs/clients.md, "Camera health").
struct CameraHealth {
  std::string camera_id;
  bool live = false;                 // a frame reached the estimator within its node.camera_lost_after_s
  double since_last_frame_s = -1;    // wall time since its last frame reached the estimator; -1 unknown
  double utilisation = 0;            // share of its frames the estimator used
  std::uint64_t refused_frames = 0;  // sent by a second writer claiming its id: refused, never used
};

// The estimator's latest status as far as cameras go: how many it receives, which it lost, and
// whether it still sees anything at all.
struct EstimatorHealth {
  bool received = false;  // false until the first estimator status arrived
  double age_s = -1;      // since it arrived (the estimator publishes every second and on a change)
  int cameras_live = 0;
  int cameras_lost = 0;
  int tracks_unobserved = 0;  // tracks held while every camera is lost: predictions only
  std::vector<CameraHealth> cameras;
};

// The library's version, the Panoptes release it belongs to (CMake's project version, also that of
// the CMake package Panoptes and of pkg-config's panoptes-client): "0.1.0".
PANOPTES_CLIENT_API std::string version();
PANOPTES_CLIENT_API int version_major();
PANOPTES_CLIENT_API int version_minor();
PANOPTES_CLIENT_API int version_patch();

class PANOPTES_CLIENT_API Client {
 public:
  // Opens the bus and subscribes. Throws ClientError naming what failed.
  explicit Client(const ClientOptions& options = {});
  ~Client();  // close(). Not from one of this client's callbacks (it would wait for itself).
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  // Push: `callback` runs on the bus's thread for every frame; keep it short. Returns a handle
  // for remove_callback. Exceptions it throws are caught and counted (Stats::callback_errors).
  using FrameCallback = std::function<void(const Frame&)>;
  int add_callback(FrameCallback callback);
  void remove_callback(int handle);  // after it returns the callback does not run

  // Pull: the next frame not yet returned by wait_for_frame (in order, from a queue of
  // ClientOptions::queue_depth), waiting up to `timeout`.
  FrameResult wait_for_frame(std::chrono::milliseconds timeout);
  // The newest frame received, if any (does not consume the queue).
  std::optional<Frame> latest() const;

  // Surface mode (docs/surface.md). The first of these calls subscribes to rt/panoptes/strokes
  // (reliable: every begin and end arrives); events before it are not seen. Callbacks run on the
  // bus's thread, one call per event, in order; exceptions are caught and counted.
  using StrokeCallback = std::function<void(const Stroke&)>;
  int add_stroke_callback(StrokeCallback callback);
  void remove_stroke_callback(int handle);  // after it returns the callback does not run
  // The next stroke event not yet returned (a queue of ClientOptions::queue_depth), waiting up to `timeout`.
  StrokeResult wait_for_stroke(std::chrono::milliseconds timeout);

  // Articulated chains (docs/articulated.md). The first of these calls subscribes to
  // rt/panoptes/chains (reliable: every grab and release arrives); what came before it is not
  // seen. Callbacks run on the bus's thread, one call per update, in order; exceptions are caught
  // and counted.
  using ChainCallback = std::function<void(const ChainUpdate&)>;
  int add_chain_callback(ChainCallback callback);
  void remove_chain_callback(int handle);  // after it returns the callback does not run
  // The next grab or release not yet returned (a queue of ClientOptions::queue_depth), waiting up
  // to `timeout`.
  GrabResult wait_for_grab_event(std::chrono::milliseconds timeout);
  // The newest chain update received, if any (subscribes on first use).
  std::optional<ChainUpdate> latest_chains();

  // The estimator's bodies (from rt/panoptes/body_descriptions, known to late joiners too); empty
  // until the first set arrived, which may be after the first frame (docs/clients.md).
  std::vector<BodyDescription> body_descriptions() const;
  // The estimator's bodies as soon as a set has arrived (at once if one has), waiting up to
  // `timeout` for the first: kTimeout if none came (no estimator yet; see status_text()), kClosed
  // if close() was called.
  DescriptionsResult wait_for_descriptions(std::chrono::milliseconds timeout);
  BodyDescription body_description(const std::string& name) const;  // throws UnknownBody
  // The subjects the estimator labels (rt/panoptes/labels, known to late joiners too); empty before
  // the first map arrived or when the estimator labels none.
  std::vector<SubjectDescription> subject_descriptions() const;

  // The rate the estimator publishes frames at (see FrameRate).
  FrameRate frame_rate() const;
  // The timecode of `frame` (its stamp on the grid of frame_rate()) when the stream is fixed-rate
  // at a whole number of frames a second; nullopt otherwise (per-camera frames, before the rate is
  // known).
  std::optional<Timecode> timecode(const Frame& frame) const;
  // A frame arrived within stale_after.
  bool connected() const;
  // "receiving (240 frames/s)", "no data for 3.2 s (last frame 1234)" or, before the first frame,
  // "no data for 1.0 s (nothing received since the client started)"; "closed" after close().
  std::string status_text() const;
  Stats stats() const;
  // The cameras as the estimator's latest status reports them (received == false before one).
  EstimatorHealth estimator_health() const;
  // The DDS profile file and domain the client opened (for diagnostics: "which bus am I on?").
  std::string profile_file() const;
  int domain_id() const;
  // The up axis of every position, velocity and orientation this client returns: "z" or "y".
  std::string up_axis() const;

  // Stops delivery and wakes wait_for_frame and the other waits (kClosed). Idempotent; may be called from a
  // callback. After it returns (called from another thread) no callback is running or will run.
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace panoptes::client
