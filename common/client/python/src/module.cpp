// SPDX-License-Identifier: Apache-2.0
// panoptes._panoptes: the Python binding of the client library (panoptes/client/client.h), wrapped
// by the pure-Python package `panoptes` (docs/clients.md, "Python"). Frames are the library's own
// C++ objects; vectors are handed to Python as NumPy float64 arrays (copies) when read.
#include <array>
#include <cstddef>
#include <cstdio>
#include <string>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "panoptes/client/client.h"
#include "py_client.h"

namespace py = pybind11;
using namespace pybind11::literals;

namespace panoptes::python {
namespace {

template <std::size_t N>
py::array_t<double> to_array(const std::array<double, N>& values) {
  return py::array_t<double>(static_cast<py::ssize_t>(N), values.data());
}

// (N, 3) array of points.
py::array_t<double> to_points(const std::vector<client::Vec3>& points) {
  py::array_t<double> out({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
  auto view = out.mutable_unchecked<2>();
  for (std::size_t i = 0; i < points.size(); ++i)
    for (std::size_t k = 0; k < 3; ++k)
      view(static_cast<py::ssize_t>(i), static_cast<py::ssize_t>(k)) = points[i][k];
  return out;
}

std::string vec_text(const client::Vec3& v) {
  char buffer[96];
  std::snprintf(buffer, sizeof buffer, "[%.4f, %.4f, %.4f]", v[0], v[1], v[2]);
  return buffer;
}

void bind_latency(py::module_& m) {
  py::class_<client::Latency>(
      m, "Latency",
      "Latency of a frame in nanoseconds (int). Stages measured on different hosts are on "
      "the common time base; 0 means unknown.")
      .def_readonly("capture_to_publish_ns", &client::Latency::capture_to_publish_ns,
                    "mid-exposure -> the estimator wrote the frame")
      .def_readonly("publish_to_receive_ns", &client::Latency::publish_to_receive_ns,
                    "the estimator wrote it -> this client received it")
      .def_readonly("capture_to_receive_ns", &client::Latency::capture_to_receive_ns,
                    "the total an application sees")
      .def_readonly("camera_ns", &client::Latency::camera_ns,
                    "mid-exposure -> camera_node published the 2D features")
      .def_readonly("network_ns", &client::Latency::network_ns,
                    "camera_node published -> estimator_node received")
      .def_readonly("queue_ns", &client::Latency::queue_ns,
                    "waiting in the estimator's inbox (its latency window)")
      .def_readonly("update_ns", &client::Latency::update_ns, "the filter update")
      .def_readonly("output_ns", &client::Latency::output_ns, "the update -> the frame was written")
      .def("__repr__", [](const client::Latency& l) {
        return "<panoptes.Latency capture_to_receive " + std::to_string(l.capture_to_receive_ns) + " ns>";
      });
}

void bind_body(py::module_& m) {
  py::class_<client::RigidBody>(
      m, "RigidBody",
      "A rigid body in a frame (every defined body, tracked or not). When tracking_valid "
      "is False the pose fields are zero (identity orientation). Arrays are float64 "
      "copies.")
      .def_readonly("name", &client::RigidBody::name, "name from the bodies file (str)")
      .def_readonly("id", &client::RigidBody::id, "1-based position in the bodies file (int)")
      .def_readonly("tracking_valid", &client::RigidBody::tracking_valid, "the pose is tracked (bool)")
      .def_property_readonly(
          "position", [](const client::RigidBody& b) { return to_array(b.position); },
          "m, world: array of shape (3,)")
      .def_property_readonly(
          "orientation", [](const client::RigidBody& b) { return to_array(b.orientation); },
          "unit quaternion x, y, z, w (body frame -> world): array of shape (4,)")
      .def_property_readonly(
          "linear_velocity", [](const client::RigidBody& b) { return to_array(b.linear_velocity); },
          "m/s, world: array of shape (3,)")
      .def_property_readonly(
          "angular_velocity", [](const client::RigidBody& b) { return to_array(b.angular_velocity); },
          "rad/s, world: array of shape (3,)")
      .def_property_readonly(
          "sigma", [](const client::RigidBody& b) { return to_array(b.sigma); },
          "1-sigma: x, y, z (m), rotation about x, y, z (rad): array of shape (6,)")
      .def_readonly("quality", &client::RigidBody::quality, "fraction of its markers seen recently, 0..1")
      .def_readonly("mean_marker_error", &client::RigidBody::mean_marker_error,
                    "m, labelled markers against the layout")
      .def_readonly("prediction_horizon_ns", &client::RigidBody::prediction_horizon_ns,
                    "the pose is predicted this far past the frame's stamp_ns")
      .def_readonly("cameras", &client::RigidBody::cameras, "cameras that saw it recently")
      .def("__repr__", [](const client::RigidBody& b) {
        return "<panoptes.RigidBody " + std::to_string(b.id) + " '" + b.name + "' " +
               (b.tracking_valid ? "tracked at " + vec_text(b.position) : std::string("not tracked")) + ">";
      });
}

void bind_marker(py::module_& m) {
  py::class_<client::Marker>(
      m, "Marker",
      "A 3D marker track with its label: labelled markers belong to a tracked body "
      "(body, body_marker), unlabelled ones are loose (body == '', body_marker == -1).")
      .def_readonly("id", &client::Marker::id, "stable while tracked (int)")
      .def_property_readonly(
          "position", [](const client::Marker& k) { return to_array(k.position); },
          "m, world: array of shape (3,)")
      .def_property_readonly(
          "velocity", [](const client::Marker& k) { return to_array(k.velocity); },
          "m/s: array of shape (3,)")
      .def_property_readonly(
          "covariance", [](const client::Marker& k) { return to_array(k.covariance); },
          "position covariance, m^2: xx xy xz yy yz zz, array of shape (6,)")
      .def_readonly("cameras", &client::Marker::cameras, "cameras that updated it recently")
      .def_readonly("occluded", &client::Marker::occluded,
                    "coasting: no camera saw it lately, position predicted")
      .def_readonly("body", &client::Marker::body, "the body it belongs to, '' if unlabelled")
      .def_readonly("body_marker", &client::Marker::body_marker,
                    "index in the body's marker layout, -1 if unlabelled")
      .def_property_readonly(
          "labelled", [](const client::Marker& k) { return k.labelled(); }, "it belongs to a body (bool)")
      .def_readonly("subject", &client::Marker::subject,
                    "the subject whose marker it is (rt/panoptes/labels), '' if unnamed")
      .def_readonly("name", &client::Marker::name, "its marker-set name, e.g. 'R.ASIS'; '' if unnamed")
      .def_property_readonly(
          "named", [](const client::Marker& k) { return k.named(); }, "it carries a marker-set name (bool)")
      .def("__repr__", [](const client::Marker& k) {
        return "<panoptes.Marker " + std::to_string(k.id) + " " +
               (k.labelled() ? k.body + "[" + std::to_string(k.body_marker) + "]"
                             : std::string("unlabelled")) +
               " at " + vec_text(k.position) + ">";
      });
}

void bind_frame(py::module_& m) {
  py::class_<client::SubjectMarkers>(m, "SubjectMarkers",
                                     "The named markers of one subject in one frame (Frame.subject(name)).")
      .def_readonly("subject", &client::SubjectMarkers::subject, "str")
      .def(
          "marker", [](const client::SubjectMarkers& s, const std::string& name) { return s.marker(name); },
          "name"_a, py::return_value_policy::reference_internal,
          "marker(name) -> Marker or None: the marker carrying that name in the frame (None: hidden or "
          "not named yet)")
      .def(
          "markers",
          [](const client::SubjectMarkers& s) {
            py::list out;
            for (const client::Marker* marker : s.markers()) out.append(*marker);
            return out;
          },
          "markers() -> list of Marker: every marker of the subject named in the frame");
  py::class_<client::Frame>(
      m, "Frame",
      "One processed camera frame of the estimator: bodies and markers with their capture "
      "stamp and latency. Times are int nanoseconds on the common (wall) clock.")
      .def_readonly("frame_number", &client::Frame::frame_number, "from 1 in each estimator run")
      .def_readonly("stamp_ns", &client::Frame::stamp_ns, "mid-exposure capture time, common clock")
      .def_readonly("publish_ns", &client::Frame::publish_ns, "the estimator wrote it")
      .def_readonly("receive_ns", &client::Frame::receive_ns, "this client received it (its system clock)")
      .def_readonly("source_camera", &client::Frame::source_camera, "camera whose frame produced this update")
      .def_readonly("source_frame", &client::Frame::source_frame, "that camera's frame number")
      .def_readonly("latency", &client::Frame::latency, "a Latency")
      .def_readonly("bodies", &client::Frame::bodies, "list of RigidBody: every defined body, tracked or not")
      .def_readonly("markers", &client::Frame::markers, "list of Marker: labelled and unlabelled")
      .def(
          "body", [](const client::Frame& f, const std::string& name) { return f.body(name); }, "name"_a,
          py::return_value_policy::reference_internal,
          "body(name) -> RigidBody or None: the body of that name in this frame")
      .def(
          "unlabelled_markers", [](const client::Frame& f) { return to_points(f.unlabelled_markers()); },
          "unlabelled_markers() -> array of shape (N, 3): positions (m, world) of the markers of no body")
      .def(
          "subject", [](const client::Frame& f, const std::string& name) { return f.subject(name); },
          "name"_a, py::keep_alive<0, 1>(),
          "subject(name) -> SubjectMarkers: frame.subject('s1').marker('R.ASIS') (docs/marker_sets.md)")
      .def("__repr__", [](const client::Frame& f) {
        return "<panoptes.Frame " + std::to_string(f.frame_number) +
               " stamp_ns=" + std::to_string(f.stamp_ns) + " " + std::to_string(f.bodies.size()) +
               " bodies " + std::to_string(f.markers.size()) + " markers>";
      });
}

void bind_descriptions_and_stats(py::module_& m) {
  py::class_<client::BodyDescription>(
      m, "BodyDescription",
      "A body of the estimator's bodies file: name, id, kind and marker layout (Client.body_descriptions()).")
      .def_readonly("name", &client::BodyDescription::name, "str")
      .def_readonly("id", &client::BodyDescription::id, "1-based position in the bodies file")
      .def_readonly("kind", &client::BodyDescription::kind, "'passive', 'led7' or 'rig' (an inside-out rig)")
      .def_property_readonly(
          "markers", [](const client::BodyDescription& d) { return to_points(d.markers); },
          "marker layout, m, body frame: array of shape (N, 3)")
      .def("__repr__", [](const client::BodyDescription& d) {
        return "<panoptes.BodyDescription " + std::to_string(d.id) + " '" + d.name + "' " + d.kind + ", " +
               std::to_string(d.markers.size()) + " markers>";
      });
  py::class_<client::SubjectDescription>(
      m, "SubjectDescription",
      "A subject the estimator labels: its marker set's names and sticks (Client.subject_descriptions()).")
      .def_readonly("name", &client::SubjectDescription::name, "str")
      .def_readonly("marker_set", &client::SubjectDescription::marker_set, "str")
      .def_readonly("markers", &client::SubjectDescription::markers, "list of str")
      .def_readonly("sticks", &client::SubjectDescription::sticks, "list of (str, str): markers drawn joined")
      .def("__repr__", [](const client::SubjectDescription& d) {
        return "<panoptes.SubjectDescription '" + d.name + "' (" + d.marker_set + ", " +
               std::to_string(d.markers.size()) + " markers)>";
      });
  py::class_<client::Stats>(m, "Stats", "Counters of a Client since it was opened.")
      .def_readonly("frames_received", &client::Stats::frames_received)
      .def_readonly(
          "frames_dropped", &client::Stats::frames_dropped,
          "overflowed the wait_for_frame queue (queue_depth); counted once wait_for_frame was called")
      .def_readonly("frames_missed", &client::Stats::frames_missed,
                    "gaps in frame_number: not delivered by the bus")
      .def_readonly("frames_malformed", &client::Stats::frames_malformed, "counted and ignored")
      .def_readonly("descriptions_received", &client::Stats::descriptions_received)
      .def_readonly("descriptions_malformed", &client::Stats::descriptions_malformed, "counted and ignored")
      .def_readonly("estimator_restarts", &client::Stats::estimator_restarts,
                    "frame_number went back: a new estimator run")
      .def_readonly("callback_errors", &client::Stats::callback_errors,
                    "exceptions raised by callbacks (caught)")
      .def_readonly("strokes_received", &client::Stats::strokes_received, "stroke events (surface mode)")
      .def_readonly("strokes_malformed", &client::Stats::strokes_malformed, "counted and ignored")
      .def_readonly("strokes_dropped", &client::Stats::strokes_dropped,
                    "overflowed the wait_for_stroke queue")
      .def_readonly("labels_received", &client::Stats::labels_received,
                    "rt/panoptes/labels maps (names of subjects' markers)")
      .def_readonly("labels_malformed", &client::Stats::labels_malformed, "counted and ignored")
      .def_readonly("last_error", &client::Stats::last_error,
                    "why the last malformed sample was ignored, or the last callback's exception")
      .def("__repr__", [](const client::Stats& s) {
        return "<panoptes.Stats received=" + std::to_string(s.frames_received) +
               " dropped=" + std::to_string(s.frames_dropped) + " missed=" + std::to_string(s.frames_missed) +
               " malformed=" + std::to_string(s.frames_malformed) +
               " restarts=" + std::to_string(s.estimator_restarts) +
               " callback_errors=" + std::to_string(s.callback_errors) + ">";
      });
}

// Camera health as the estimator reports it (docs/clients.md, "Camera health").
void bind_health(py::module_& m) {
  py::class_<client::CameraHealth>(m, "CameraHealth", "One camera as the estimator sees it.")
      .def_readonly("camera_id", &client::CameraHealth::camera_id)
      .def_readonly("live", &client::CameraHealth::live,
                    "a frame reached the estimator within its node.camera_lost_after_s")
      .def_readonly("since_last_frame_s", &client::CameraHealth::since_last_frame_s,
                    "wall time since its last frame reached the estimator; -1 unknown")
      .def_readonly("utilisation", &client::CameraHealth::utilisation,
                    "share of its frames the estimator used")
      .def_readonly("refused_frames", &client::CameraHealth::refused_frames,
                    "sent by a second writer claiming its id: refused")
      .def("__repr__", [](const client::CameraHealth& c) {
        return "<panoptes.CameraHealth " + c.camera_id + (c.live ? " live" : " lost") + ">";
      });
  py::class_<client::FrameRate>(m, "FrameRate", "The estimator's frame rate as its frames' stamps show it.")
      .def_readonly("fixed", &client::FrameRate::fixed, "the newest frame was a fixed-rate frame (bool)")
      .def_readonly("hz", &client::FrameRate::hz,
                    "fixed: the grid's rate (median stamp interval); else the mean rate of the frames; "
                    "0 before two frames")
      .def("__repr__", [](const client::FrameRate& r) {
        return "<panoptes.FrameRate " + std::to_string(r.hz) + " Hz" + (r.fixed ? " fixed>" : ">");
      });
  py::class_<client::Timecode>(m, "Timecode", "A fixed-rate frame's SMPTE-style timecode (docs/frames.md).")
      .def_readonly("hours", &client::Timecode::hours)
      .def_readonly("minutes", &client::Timecode::minutes)
      .def_readonly("seconds", &client::Timecode::seconds)
      .def_readonly("frames", &client::Timecode::frames, "0 .. rate_hz - 1 within the second")
      .def_readonly("rate_hz", &client::Timecode::rate_hz)
      .def_readonly("text", &client::Timecode::text, "'HH:MM:SS:FF'")
      .def("__repr__", [](const client::Timecode& t) { return "<panoptes.Timecode " + t.text + ">"; });
  py::class_<client::EstimatorHealth>(m, "EstimatorHealth", "The cameras in the estimator's latest status.")
      .def_readonly("received", &client::EstimatorHealth::received, "False until the first status arrived")
      .def_readonly("age_s", &client::EstimatorHealth::age_s, "seconds since that status arrived")
      .def_readonly("cameras_live", &client::EstimatorHealth::cameras_live)
      .def_readonly("cameras_lost", &client::EstimatorHealth::cameras_lost)
      .def_readonly("tracks_unobserved", &client::EstimatorHealth::tracks_unobserved,
                    "tracks held while every camera is lost: predictions only")
      .def_readonly("cameras", &client::EstimatorHealth::cameras);
}

// Surface mode (docs/surface.md): one stroke event.
void bind_stroke(py::module_& m) {
  py::class_<client::Stroke>(
      m, "Stroke",
      "One event of a stroke on the wall (surface mode, docs/surface.md): phase "
      "'begin', 'continue' or 'end'; position, velocity, acceleration in surface metres.")
      .def_property_readonly("phase",
                             [](const client::Stroke& s) {
                               return s.phase == client::StrokePhase::kBegin ? "begin"
                                      : s.phase == client::StrokePhase::kEnd ? "end"
                                                                             : "continue";
                             })
      .def_readonly("id", &client::Stroke::id, "stable for the stroke's life (int)")
      .def_readonly("stamp_ns", &client::Stroke::stamp_ns, "common clock (int)")
      .def_property_readonly(
          "position", [](const client::Stroke& s) { return py::make_tuple(s.position[0], s.position[1]); },
          "(s, t), m")
      .def_property_readonly(
          "velocity", [](const client::Stroke& s) { return py::make_tuple(s.velocity[0], s.velocity[1]); },
          "m/s")
      .def_property_readonly(
          "acceleration",
          [](const client::Stroke& s) { return py::make_tuple(s.acceleration[0], s.acceleration[1]); },
          "m/s^2")
      .def_readonly("cameras", &client::Stroke::cameras, "cameras that saw it recently")
      .def_property_readonly(
          "surface_size",
          [](const client::Stroke& s) { return py::make_tuple(s.surface_size[0], s.surface_size[1]); },
          "(width, height), m")
      .def_readonly("source_camera", &client::Stroke::source_camera)
      .def_readonly("publish_ns", &client::Stroke::publish_ns)
      .def_readonly("receive_ns", &client::Stroke::receive_ns)
      .def("__repr__", [](const client::Stroke& s) {
        return "<panoptes.Stroke " + std::to_string(s.id) + " " +
               (s.phase == client::StrokePhase::kBegin ? "begin"
                : s.phase == client::StrokePhase::kEnd ? "end"
                                                       : "continue") +
               ">";
      });
}

py::tuple vec3_tuple(const client::Vec3& v) {
  return py::make_tuple(v[0], v[1], v[2]);
}

// Articulated chains (docs/articulated.md): chain states, grab events and the update holding both.
void bind_chains(py::module_& m) {
  py::class_<client::Chain>(m, "Chain",
                            "One articulated chain after a camera frame; angles, markers and tips only "
                            "while status is 'tracking'.")
      .def_readonly("name", &client::Chain::name)
      .def_readonly("id", &client::Chain::id, "1-based position among the chains of the bodies file")
      .def_property_readonly("status",
                             [](const client::Chain& c) {
                               return c.status == client::ChainStatus::kTracking    ? "tracking"
                                      : c.status == client::ChainStatus::kAmbiguous ? "ambiguous"
                                                                                    : "not_identified";
                             })
      .def_readonly("stamp_ns", &client::Chain::stamp_ns)
      .def_readonly("joint_angles", &client::Chain::joint_angles, "rad, base first")
      .def_property_readonly(
          "markers",
          [](const client::Chain& c) {
            py::list markers;
            for (const auto& marker : c.markers) markers.append(vec3_tuple(marker));
            return markers;
          },
          "world m, base first")
      .def_readonly("marker_valid", &client::Chain::marker_valid)
      .def_property_readonly(
          "tip", [](const client::Chain& c) { return vec3_tuple(c.tip); }, "world m")
      .def_property_readonly(
          "predicted_tip", [](const client::Chain& c) { return vec3_tuple(c.predicted_tip); },
          "world m, prediction_horizon_ns ahead")
      .def_readonly("prediction_horizon_ns", &client::Chain::prediction_horizon_ns)
      .def_readonly("grabbing", &client::Chain::grabbing)
      .def("__repr__", [](const client::Chain& c) { return "<panoptes.Chain " + c.name + ">"; });
  py::class_<client::GrabEvent>(m, "GrabEvent", "A grab or release gesture of a chain (seed 000 §6.4.5).")
      .def_property_readonly(
          "kind",
          [](const client::GrabEvent& e) { return e.kind == client::GrabKind::kGrab ? "grab" : "release"; })
      .def_readonly("chain", &client::GrabEvent::chain)
      .def_readonly("chain_id", &client::GrabEvent::chain_id)
      .def_readonly("stamp_ns", &client::GrabEvent::stamp_ns, "when the bend crossed the threshold")
      .def_property_readonly(
          "tip", [](const client::GrabEvent& e) { return vec3_tuple(e.tip); }, "world m")
      .def_readonly("bend", &client::GrabEvent::bend, "rad, the sum of the joint angles")
      .def_readonly("publish_ns", &client::GrabEvent::publish_ns)
      .def_readonly("receive_ns", &client::GrabEvent::receive_ns)
      .def("__repr__", [](const client::GrabEvent& e) {
        return std::string("<panoptes.GrabEvent ") +
               (e.kind == client::GrabKind::kGrab ? "grab " : "release ") + e.chain + ">";
      });
  py::class_<client::ChainUpdate>(m, "ChainUpdate",
                                  "Every chain after one camera frame, and its grab events.")
      .def_readonly("stamp_ns", &client::ChainUpdate::stamp_ns)
      .def_readonly("publish_ns", &client::ChainUpdate::publish_ns)
      .def_readonly("receive_ns", &client::ChainUpdate::receive_ns)
      .def_readonly("source_camera", &client::ChainUpdate::source_camera)
      .def_readonly("source_frame", &client::ChainUpdate::source_frame)
      .def_readonly("chains", &client::ChainUpdate::chains)
      .def_readonly("events", &client::ChainUpdate::events)
      .def(
          "chain",
          [](const client::ChainUpdate& u, const std::string& name) -> py::object {
            const client::Chain* chain = u.chain(name);
            return chain ? py::cast(*chain) : py::none();
          },
          "name"_a, "chain(name) -> Chain or None");
}

// Instances of the data classes come from the library only: `__new__` refuses to make an empty one
// (pybind11 would hand out an object over unconstructed memory; copy.copy() would too). pybind11's
// own instances are allocated with tp_alloc, not through __new__.
void forbid_new(py::module_& m) {
  const py::cpp_function refuse([](const py::args&, const py::kwargs&) {
    throw py::type_error("panoptes frames, bodies, markers, descriptions and stats come from a Client");
  });
  for (const char* name : {"Latency", "RigidBody", "Marker", "Frame", "BodyDescription", "Stats", "Stroke",
                           "Chain", "GrabEvent", "ChainUpdate", "Timecode"})
    m.attr(name).attr("__new__") = py::staticmethod(refuse);
}

void bind_exceptions(py::module_& m) {
  // ClientError (a RuntimeError) and UnknownBody (a ClientError and a KeyError); str() of both is
  // the library's message (KeyError would quote it).
  static py::handle client_error = PyErr_NewExceptionWithDoc(
      "panoptes.ClientError",
      "The client cannot be opened (bad profile, domain or option); the message names it.",
      PyExc_RuntimeError, nullptr);
  py::dict unknown_dict;
  unknown_dict["__str__"] = py::handle(PyExc_BaseException).attr("__str__");
  static py::handle unknown_body = PyErr_NewExceptionWithDoc(
      "panoptes.UnknownBody", "No body of that name is described by the estimator; the message names it.",
      py::make_tuple(client_error, py::handle(PyExc_KeyError)).release().ptr(), unknown_dict.release().ptr());
  m.attr("ClientError") = client_error;
  m.attr("UnknownBody") = unknown_body;
  // pybind11's translator type takes the exception_ptr by value.
  py::register_exception_translator(
      [](std::exception_ptr error) {  // NOLINT(performance-unnecessary-value-param)
        try {
          if (error) std::rethrow_exception(error);
        } catch (const client::UnknownBody& e) {
          PyErr_SetString(unknown_body.ptr(), e.what());
        } catch (const client::ClientError& e) {
          PyErr_SetString(client_error.ptr(), e.what());
        }
      });
}

}  // namespace

void bind_client(py::module_& m);

}  // namespace panoptes::python

PYBIND11_MODULE(_panoptes, m) {
  m.doc() = "Binding of the Panoptes client library (libpanoptes_client.so); use the package `panoptes`.";
  using namespace panoptes::python;
  bind_exceptions(m);
  bind_latency(m);
  bind_body(m);
  bind_marker(m);
  bind_frame(m);
  bind_descriptions_and_stats(m);
  bind_health(m);
  bind_stroke(m);
  bind_chains(m);
  bind_client(m);
  forbid_new(m);
  m.def("version", &panoptes::client::version,
        "version() -> str: the client library's version, the Panoptes release (\"0.1.0\")");
  m.attr("version_info") =
      py::make_tuple(panoptes::client::version_major(), panoptes::client::version_minor(),
                     panoptes::client::version_patch());
  // Users meet these classes as panoptes.X (help(), repr of the types, pickling errors).
  for (const char* name : {"Client", "Latency", "RigidBody", "Marker", "Frame", "BodyDescription", "Stats",
                           "Stroke", "Chain", "GrabEvent", "ChainUpdate", "Timecode"})
    m.attr(name).attr("__module__") = "panoptes";
  py::module_::import("atexit").attr("register")(py::cpp_function(&PyClient::close_all_at_exit));
}
