// SPDX-License-Identifier: Apache-2.0
// The ROS 2 wire check (issue 15, docs/ros2.md): every ROS 2 message we publish, serialized by the
// code fastddsgen generated from idl/ros2.idl, must equal byte for byte a reference serialization
// written here from the upstream message definitions, independently of our IDL:
//   builtin_interfaces/Time      int32 sec, uint32 nanosec
//   std_msgs/Header              builtin_interfaces/Time stamp, string frame_id
//   geometry_msgs/Point|Vector3  float64 x, y, z
//   geometry_msgs/Quaternion     float64 x, y, z, w
//   geometry_msgs/Pose           Point position, Quaternion orientation
//   geometry_msgs/PoseStamped    Header header, Pose pose
//   geometry_msgs/Twist          Vector3 linear, Vector3 angular
//   geometry_msgs/TwistStamped   Header header, Twist twist
//   geometry_msgs/Transform      Vector3 translation, Quaternion rotation
//   geometry_msgs/TransformStamped  Header header, string child_frame_id, Transform transform
//   tf2_msgs/TFMessage           TransformStamped[] transforms
//   mocap4r2_msgs/Marker         int8 id_type, int32 marker_index, string marker_name, Point translation
//   mocap4r2_msgs/Markers        Header header, uint32 frame_number, Marker[] markers
//   mocap4r2_msgs/RigidBody      string rigid_body_name, Marker[] markers, Pose pose
//   mocap4r2_msgs/RigidBodies    Header header, uint32 frame_number, RigidBody[] rigidbodies
// (ros2/common_interfaces, ros2/rcl_interfaces, ros2/geometry2, mocap4r2_msgs 0.0.3.) ROS 2's
// middlewares put them on the wire as plain CDR (XCDR1), little endian here: the encapsulation
// header 00 01 00 00, then every primitive aligned to its size counted from the end of that header,
// strings as a uint32 length that counts the terminating NUL, the characters and the NUL, sequences
// as a uint32 element count and the elements.
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <fastdds/rtps/common/SerializedPayload.h>
#include <gtest/gtest.h>

#include "panoptes_msgs/ros2.h"
#include "panoptes_msgs/ros2PubSubTypes.h"

namespace {

namespace geometry = geometry_msgs::msg::dds_;
namespace mocap = mocap4r2_msgs::msg::dds_;
using Bytes = std::vector<std::uint8_t>;

// The reference encoder: XCDR1, little endian.
class Cdr1 {
 public:
  Cdr1() : bytes_{0x00, 0x01, 0x00, 0x00} {}

  Cdr1& int8(std::int8_t v) { return raw(&v, 1); }
  Cdr1& int32(std::int32_t v) { return raw(&v, 4); }
  Cdr1& uint32(std::uint32_t v) { return raw(&v, 4); }
  Cdr1& float64(double v) { return raw(&v, 8); }
  Cdr1& string(const std::string& s) {
    uint32(static_cast<std::uint32_t>(s.size() + 1));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
    bytes_.push_back(0);
    return *this;
  }
  Cdr1& count(std::size_t n) { return uint32(static_cast<std::uint32_t>(n)); }

  const Bytes& bytes() const { return bytes_; }

 private:
  // Aligns to the primitive's size, then appends it little endian (this machine's order, checked
  // by the test LittleEndianHost).
  Cdr1& raw(const void* value, std::size_t size) {
    while ((bytes_.size() - 4) % size != 0) bytes_.push_back(0);
    const auto* p = static_cast<const std::uint8_t*>(value);
    bytes_.insert(bytes_.end(), p, p + size);
    return *this;
  }

  Bytes bytes_;
};

// The values of the test messages; distinct so that a swapped or missing field shows.
struct Stamp {
  std::int32_t sec;
  std::uint32_t nanosec;
  std::string frame_id;
};
struct Xyz {
  double x, y, z;
};
struct Xyzw {
  double x, y, z, w;
};
struct MarkerValues {
  std::int8_t id_type;
  std::int32_t index;
  std::string name;
  Xyz p;
};

// Upstream field lists, encoded.
void encode(Cdr1& cdr, const Stamp& h) {
  cdr.int32(h.sec).uint32(h.nanosec).string(h.frame_id);
}
void encode(Cdr1& cdr, const Xyz& v) {
  cdr.float64(v.x).float64(v.y).float64(v.z);
}
void encode(Cdr1& cdr, const Xyzw& q) {
  cdr.float64(q.x).float64(q.y).float64(q.z).float64(q.w);
}
void encode(Cdr1& cdr, const MarkerValues& m) {
  cdr.int8(m.id_type).int32(m.index).string(m.name);
  encode(cdr, m.p);
}

// The same values in the generated types.
std_msgs::msg::dds_::Header_ header_of(const Stamp& h) {
  std_msgs::msg::dds_::Header_ out;
  out.stamp().sec(h.sec);
  out.stamp().nanosec(h.nanosec);
  out.frame_id(h.frame_id);
  return out;
}
template <class Out>  // geometry_msgs Point_ or Vector3_
Out xyz_of(const Xyz& v) {
  Out out;
  out.x(v.x);
  out.y(v.y);
  out.z(v.z);
  return out;
}
geometry::Quaternion_ quaternion_of(const Xyzw& q) {
  geometry::Quaternion_ out;
  out.x(q.x);
  out.y(q.y);
  out.z(q.z);
  out.w(q.w);
  return out;
}
mocap::Marker_ marker_of(const MarkerValues& m) {
  mocap::Marker_ out;
  out.id_type(m.id_type);
  out.marker_index(m.index);
  out.marker_name(m.name);
  out.translation(xyz_of<geometry::Point_>(m.p));
  return out;
}

template <class PubSubType, class T>
Bytes serialize_generated(T& sample) {
  PubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&sample)());
  EXPECT_TRUE(type.serialize(&sample, &payload));
  return Bytes(payload.data, payload.data + payload.length);
}

// Header frame ids of lengths 5 and 2 (with NUL): the doubles after them need 3 and 6 bytes of padding.
const Stamp kStamp{-2, 300000000, "worl"};
const Stamp kOtherStamp{1700000000, 999999999, "w"};
const Xyz kPosition{1.5, -2.25, 3.125};
const Xyz kAngular{-0.5, 0.75, -1e-9};
const Xyzw kRotation{0.1, -0.2, 0.3, 0.9};
const MarkerValues kLabelled{2, 3, "head/3", {0.25, 0.5, 1.75}};
const MarkerValues kUnlabelled{1, 1234567, "", {-4.0, 5.5, 0.001}};
const MarkerValues kNamed{0, -1, "tool/10", {7.0, 8.0, 9.0}};

TEST(Ros2Wire, LittleEndianHost) {
  const std::uint32_t one = 1;
  std::uint8_t first = 0;
  std::memcpy(&first, &one, 1);
  ASSERT_EQ(first, 1) << "the reference encoder writes this machine's byte order, assumed little endian";
}

// The reference encoder itself, against bytes worked out by hand.
TEST(Ros2Wire, ReferenceEncoderMatchesHandWrittenBytes) {
  Cdr1 cdr;
  encode(cdr, MarkerValues{2, 7, "a/0", {1.0, 2.0, 3.0}});
  const Bytes expected = {0x00, 0x01, 0x00, 0x00,                           // encapsulation: CDR_LE
                          0x02, 0x00, 0x00, 0x00,                           // id_type, 3 bytes padding
                          0x07, 0x00, 0x00, 0x00,                           // marker_index
                          0x04, 0x00, 0x00, 0x00, 'a',  '/',  '0',  0x00,   // marker_name
                          0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xf0, 0x3f,   // x = 1.0
                          0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x40,   // y = 2.0
                          0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x08, 0x40};  // z = 3.0
  EXPECT_EQ(cdr.bytes(), expected);
  Cdr1 header;
  encode(header, Stamp{1, 2, "ab"});
  header.float64(0.0);
  const Bytes expected_header = {0x00, 0x01, 0x00, 0x00,                           // encapsulation
                                 0x01, 0x00, 0x00, 0x00,                           // sec
                                 0x02, 0x00, 0x00, 0x00,                           // nanosec
                                 0x03, 0x00, 0x00, 0x00, 'a',  'b',  0x00,         // frame_id
                                 0x00,                                             // padding to 8
                                 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00};  // 0.0
  EXPECT_EQ(header.bytes(), expected_header);
}

TEST(Ros2Wire, PoseStamped) {
  geometry::PoseStamped_ sample;
  sample.header(header_of(kStamp));
  sample.pose().position(xyz_of<geometry::Point_>(kPosition));
  sample.pose().orientation(quaternion_of(kRotation));
  Cdr1 reference;
  encode(reference, kStamp);
  encode(reference, kPosition);
  encode(reference, kRotation);
  EXPECT_EQ(serialize_generated<geometry::PoseStamped_PubSubType>(sample), reference.bytes());
}

TEST(Ros2Wire, TwistStamped) {
  geometry::TwistStamped_ sample;
  sample.header(header_of(kOtherStamp));
  sample.twist().linear(xyz_of<geometry::Vector3_>(kPosition));
  sample.twist().angular(xyz_of<geometry::Vector3_>(kAngular));
  Cdr1 reference;
  encode(reference, kOtherStamp);
  encode(reference, kPosition);
  encode(reference, kAngular);
  EXPECT_EQ(serialize_generated<geometry::TwistStamped_PubSubType>(sample), reference.bytes());
}

TEST(Ros2Wire, TFMessage) {
  tf2_msgs::msg::dds_::TFMessage_ sample;
  Cdr1 reference;
  reference.count(2);
  const std::vector<std::pair<Stamp, std::string>> frames = {{kStamp, "head"}, {kOtherStamp, "mocap/tool"}};
  for (const auto& [stamp, child] : frames) {
    geometry::TransformStamped_ transform;
    transform.header(header_of(stamp));
    transform.child_frame_id(child);
    transform.transform().translation(xyz_of<geometry::Vector3_>(kPosition));
    transform.transform().rotation(quaternion_of(kRotation));
    sample.transforms().push_back(transform);
    encode(reference, stamp);
    reference.string(child);
    encode(reference, kPosition);
    encode(reference, kRotation);
  }
  EXPECT_EQ(serialize_generated<tf2_msgs::msg::dds_::TFMessage_PubSubType>(sample), reference.bytes());
}

TEST(Ros2Wire, EmptyTFMessage) {
  tf2_msgs::msg::dds_::TFMessage_ sample;
  Cdr1 reference;
  reference.count(0);
  EXPECT_EQ(serialize_generated<tf2_msgs::msg::dds_::TFMessage_PubSubType>(sample), reference.bytes());
}

TEST(Ros2Wire, Markers) {
  mocap::Markers_ sample;
  sample.header(header_of(kStamp));
  sample.frame_number(4000000000U);
  Cdr1 reference;
  encode(reference, kStamp);
  reference.uint32(4000000000U).count(3);
  for (const auto& marker : {kLabelled, kUnlabelled, kNamed}) {
    sample.markers().push_back(marker_of(marker));
    encode(reference, marker);
  }
  EXPECT_EQ(serialize_generated<mocap::Markers_PubSubType>(sample), reference.bytes());
}

TEST(Ros2Wire, RigidBodies) {
  mocap::RigidBodies_ sample;
  sample.header(header_of(kOtherStamp));
  sample.frame_number(17);
  Cdr1 reference;
  encode(reference, kOtherStamp);
  reference.uint32(17).count(3);
  const std::vector<std::pair<std::string, std::vector<MarkerValues>>> bodies = {
      {"head", {kLabelled, kNamed}}, {"t", {}}, {"tool_with_a_longer_name", {kUnlabelled}}};
  for (const auto& [name, markers] : bodies) {
    mocap::RigidBody_ body;
    body.rigid_body_name(name);
    reference.string(name).count(markers.size());
    for (const auto& marker : markers) {
      body.markers().push_back(marker_of(marker));
      encode(reference, marker);
    }
    body.pose().position(xyz_of<geometry::Point_>(kPosition));
    body.pose().orientation(quaternion_of(kRotation));
    encode(reference, kPosition);
    encode(reference, kRotation);
    sample.rigidbodies().push_back(body);
  }
  EXPECT_EQ(serialize_generated<mocap::RigidBodies_PubSubType>(sample), reference.bytes());
}

// ROS 2's middlewares match topics by these type names; ROS 2 messages have no key.
template <class PubSubType>
void expect_ros2_type(const std::string& name) {
  PubSubType type;
  EXPECT_EQ(std::string(type.getName()), name);
  EXPECT_FALSE(type.m_isGetKeyDefined) << name << " must be unkeyed";
}

TEST(Ros2Wire, TypeNamesAreRos2sAndUnkeyed) {
  expect_ros2_type<builtin_interfaces::msg::dds_::Time_PubSubType>("builtin_interfaces::msg::dds_::Time_");
  expect_ros2_type<std_msgs::msg::dds_::Header_PubSubType>("std_msgs::msg::dds_::Header_");
  expect_ros2_type<geometry::PoseStamped_PubSubType>("geometry_msgs::msg::dds_::PoseStamped_");
  expect_ros2_type<geometry::TwistStamped_PubSubType>("geometry_msgs::msg::dds_::TwistStamped_");
  expect_ros2_type<geometry::TransformStamped_PubSubType>("geometry_msgs::msg::dds_::TransformStamped_");
  expect_ros2_type<tf2_msgs::msg::dds_::TFMessage_PubSubType>("tf2_msgs::msg::dds_::TFMessage_");
  expect_ros2_type<mocap::Marker_PubSubType>("mocap4r2_msgs::msg::dds_::Marker_");
  expect_ros2_type<mocap::Markers_PubSubType>("mocap4r2_msgs::msg::dds_::Markers_");
  expect_ros2_type<mocap::RigidBody_PubSubType>("mocap4r2_msgs::msg::dds_::RigidBody_");
  expect_ros2_type<mocap::RigidBodies_PubSubType>("mocap4r2_msgs::msg::dds_::RigidBodies_");
}

// int8 as upstream: a negative id_type value (not one of the constants, but representable) reads back.
TEST(Ros2Wire, MarkerIdTypeIsSigned) {
  mocap::Marker_ marker;
  marker.id_type(-1);
  EXPECT_LT(marker.id_type(), 0);
}

}  // namespace
