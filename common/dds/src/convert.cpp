// SPDX-License-Identifier: Apache-2.0
#include "panoptes/dds/convert.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace panoptes::dds {

msg::FeatureFrame to_message(const FeatureFrame& frame) {
  msg::FeatureFrame message;
  message.camera_id(frame.camera_id);
  message.frame(frame.frame);
  message.stamp_ns(frame.stamp_ns);
  message.arrival_ns(frame.arrival_ns);
  message.processing_ns(frame.processing_ns);
  message.publish_ns(frame.publish_ns);
  auto& blobs = message.blobs();
  blobs.reserve(frame.blobs.size());
  for (const Blob& blob : frame.blobs) {
    msg::Blob b;
    b.x(static_cast<float>(blob.x));
    b.y(static_cast<float>(blob.y));
    b.area(static_cast<float>(blob.area));
    b.sum(static_cast<float>(blob.sum));
    b.peak(static_cast<uint16_t>(std::clamp(blob.peak, 0, 65535)));
    b.m20(static_cast<float>(blob.m20));
    b.m11(static_cast<float>(blob.m11));
    b.m02(static_cast<float>(blob.m02));
    const auto coordinate = [](int value) { return static_cast<uint16_t>(std::clamp(value, 0, 65535)); };
    b.bbox({coordinate(blob.x0), coordinate(blob.y0), coordinate(blob.x1), coordinate(blob.y1)});
    blobs.push_back(b);
  }
  return message;
}

FeatureFrame from_message(const msg::FeatureFrame& message) {
  FeatureFrame frame;
  frame.camera_id = message.camera_id();
  frame.frame = message.frame();
  frame.stamp_ns = message.stamp_ns();
  frame.arrival_ns = message.arrival_ns();
  frame.processing_ns = message.processing_ns();
  frame.publish_ns = message.publish_ns();
  frame.blobs.reserve(message.blobs().size());
  for (const msg::Blob& b : message.blobs()) {
    Blob blob;
    blob.x = b.x();
    blob.y = b.y();
    blob.area = b.area();
    blob.sum = b.sum();
    blob.peak = b.peak();
    blob.m20 = b.m20();
    blob.m11 = b.m11();
    blob.m02 = b.m02();
    blob.x0 = b.bbox()[0];
    blob.y0 = b.bbox()[1];
    blob.x1 = b.bbox()[2];
    blob.y1 = b.bbox()[3];
    frame.blobs.push_back(blob);
  }
  return frame;
}

msg::Track to_message(const TrackRecord& track) {
  msg::Track message;
  message.id(track.id);
  message.position({track.p.x(), track.p.y(), track.p.z()});
  message.velocity({track.v.x(), track.v.y(), track.v.z()});
  message.covariance(track.position_covariance);
  message.status(static_cast<uint8_t>(track.status));
  message.cameras(static_cast<uint16_t>(std::clamp(track.cameras, 0, 65535)));
  return message;
}

TrackRecord from_message(const msg::Track& message, TimeNs stamp_ns) {
  TrackRecord track;
  track.stamp_ns = stamp_ns;
  track.id = message.id();
  track.p = Eigen::Vector3d(message.position()[0], message.position()[1], message.position()[2]);
  track.v = Eigen::Vector3d(message.velocity()[0], message.velocity()[1], message.velocity()[2]);
  track.position_covariance = message.covariance();
  track.status = message.status() <= 2 ? static_cast<TrackStatus>(message.status()) : TrackStatus::kConfirmed;
  track.cameras = message.cameras();
  return track;
}

msg::CameraInfo to_camera_info(const std::string& camera_id, const CameraIntrinsics& intrinsics,
                               const std::optional<RigidTransform>& T_world_cam, bool moving) {
  msg::CameraInfo info;
  info.camera_id(camera_id);
  info.moving(moving);
  info.width(static_cast<uint32_t>(intrinsics.width));
  info.height(static_cast<uint32_t>(intrinsics.height));
  info.K({intrinsics.fx, intrinsics.fy, intrinsics.cx, intrinsics.cy});
  info.distortion(intrinsics.distortion);
  info.has_pose(T_world_cam.has_value());
  if (T_world_cam) {
    msg::Pose3 pose;
    pose.position({T_world_cam->t.x(), T_world_cam->t.y(), T_world_cam->t.z()});
    pose.orientation({T_world_cam->q.x(), T_world_cam->q.y(), T_world_cam->q.z(), T_world_cam->q.w()});
    info.T_world_cam(pose);
  }
  return info;
}

namespace {

constexpr std::size_t kMaxIdLength = 256;
constexpr std::uint32_t kMaxImageSide = 65536;

template <std::size_t N>
bool all_finite(const std::array<double, N>& values) {
  return std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); });
}

}  // namespace

bool plausible_id(const std::string& id) {
  return !id.empty() && id.size() <= kMaxIdLength && std::none_of(id.begin(), id.end(), [](char c) {
    return static_cast<unsigned char>(c) < 0x20 || c == 0x7f;
  });
}

std::string_view camera_info_problem(const msg::CameraInfo& info) {
  if (!plausible_id(info.camera_id())) return "bad_camera_id";
  if (info.width() > kMaxImageSide || info.height() > kMaxImageSide) return "image_size_out_of_range";
  if (!all_finite(info.K()) || !all_finite(info.distortion()) || !std::isfinite(info.nominal_rate_hz()))
    return "non_finite_calibration";
  if (info.has_pose()) {
    const auto& pose = info.T_world_cam();
    if (!all_finite(pose.position()) || !all_finite(pose.orientation())) return "non_finite_calibration";
    const auto& q = pose.orientation();
    if (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] < 1e-12) return "zero_quaternion";
  }
  return {};
}

std::optional<CameraCalibration> calibration_from(const msg::CameraInfo& info) {
  if (!camera_info_problem(info).empty()) return std::nullopt;
  if (info.K()[0] <= 0.0 || info.K()[1] <= 0.0 || info.width() == 0 || info.height() == 0)
    return std::nullopt;
  CameraCalibration calibration;
  calibration.id = info.camera_id();
  calibration.intrinsics.width = static_cast<int>(info.width());
  calibration.intrinsics.height = static_cast<int>(info.height());
  calibration.intrinsics.fx = info.K()[0];
  calibration.intrinsics.fy = info.K()[1];
  calibration.intrinsics.cx = info.K()[2];
  calibration.intrinsics.cy = info.K()[3];
  calibration.intrinsics.distortion = info.distortion();
  calibration.moving = info.moving();
  if (info.has_pose()) {
    const auto& pose = info.T_world_cam();
    RigidTransform T;
    T.t = Eigen::Vector3d(pose.position()[0], pose.position()[1], pose.position()[2]);
    T.q = Eigen::Quaterniond(pose.orientation()[3], pose.orientation()[0], pose.orientation()[1],
                             pose.orientation()[2])
              .normalized();
    calibration.T_world_cam = T;
  }
  return calibration;
}

msg::SystemCalibration to_message(const SystemCalibration& calibration, TimeNs stamp_ns) {
  msg::SystemCalibration message;
  message.stamp_ns(stamp_ns);
  for (const auto& camera : calibration.cameras) {
    msg::CameraCalibration out;
    out.camera_id(camera.id);
    out.width(static_cast<std::uint32_t>(camera.intrinsics.width));
    out.height(static_cast<std::uint32_t>(camera.intrinsics.height));
    out.K({camera.intrinsics.fx, camera.intrinsics.fy, camera.intrinsics.cx, camera.intrinsics.cy});
    out.distortion(camera.intrinsics.distortion);
    out.has_pose(camera.T_world_cam.has_value());
    if (camera.T_world_cam) {
      msg::Pose3 pose;
      const auto& T = *camera.T_world_cam;
      pose.position({T.t.x(), T.t.y(), T.t.z()});
      pose.orientation({T.q.x(), T.q.y(), T.q.z(), T.q.w()});
      out.T_world_cam(pose);
    }
    message.cameras().push_back(out);
  }
  return message;
}

msg::BodyPose to_message(const PoseRecord& pose) {
  msg::BodyPose message;
  message.name(pose.body);
  message.stamp_ns(pose.stamp_ns);
  msg::Pose3 pose3;
  pose3.position({pose.p.x(), pose.p.y(), pose.p.z()});
  pose3.orientation({pose.q.x(), pose.q.y(), pose.q.z(), pose.q.w()});
  message.pose(pose3);
  message.linear_velocity({pose.v.x(), pose.v.y(), pose.v.z()});
  message.angular_velocity({pose.w.x(), pose.w.y(), pose.w.z()});
  std::array<double, 36> covariance{};  // diagonal: the filter's marginal variances
  for (std::size_t k = 0; k < 6; ++k) covariance[k * 6 + k] = pose.sigma[k] * pose.sigma[k];
  message.covariance(covariance);
  message.quality(static_cast<float>(pose.quality));
  message.prediction_horizon_ns(pose.horizon_ns);
  return message;
}

PoseRecord from_message(const msg::BodyPose& message) {
  PoseRecord pose;
  pose.body = message.name();
  pose.stamp_ns = message.stamp_ns();
  const auto& p = message.pose().position();
  const auto& q = message.pose().orientation();
  pose.p = Eigen::Vector3d(p[0], p[1], p[2]);
  pose.q = Eigen::Vector4d(q[0], q[1], q[2], q[3]);
  const auto& v = message.linear_velocity();
  const auto& w = message.angular_velocity();
  pose.v = Eigen::Vector3d(v[0], v[1], v[2]);
  pose.w = Eigen::Vector3d(w[0], w[1], w[2]);
  for (std::size_t k = 0; k < 6; ++k)
    pose.sigma[k] = std::sqrt(std::max(0.0, message.covariance()[k * 6 + k]));
  pose.quality = message.quality();
  pose.horizon_ns = message.prediction_horizon_ns();
  return pose;
}

}  // namespace panoptes::dds
