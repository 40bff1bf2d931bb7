// SPDX-License-Identifier: Apache-2.0
// The ros2idl schemas of recordings (issue 32): rosbag2's message-definition encoding, one
// "IDL: panoptes/msg/<Name>" section per struct with the message's own type first, as Foxglove's
// reader needs (integration/test_recording.sh decodes a real recording with Foxglove's decoders).
#include <gtest/gtest.h>

#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "panoptes/dds/bus.h"
#include "panoptes/recorder/ros2_naming.h"

namespace panoptes::recorder {
namespace {

struct Section {
  std::string type;  // after "IDL: "
  std::string text;  // the lines after the delimiter
};

// The schema cut at its delimiters; fails the test on text before the first one.
std::vector<Section> sections(const std::string& schema) {
  const std::string delimiter(80, '=');
  std::vector<Section> out;
  std::istringstream lines(schema);
  std::string line;
  bool expect_type = false;
  while (std::getline(lines, line)) {
    if (line == delimiter) {
      expect_type = true;
    } else if (expect_type) {
      EXPECT_EQ(line.rfind("IDL: ", 0), 0U) << line;
      out.push_back({line.substr(5), ""});
      expect_type = false;
    } else {
      EXPECT_FALSE(out.empty()) << "text before the first delimiter: " << line;
      if (!out.empty()) out.back().text += line + "\n";
    }
  }
  return out;
}

TEST(Ros2IdlSchema, OwnTypeFirstThenEachDependencyInItsOwnSection) {
  const auto schema = ros2idl_schema("panoptes/msg/MocapFrame");
  const auto parts = sections(schema);
  std::vector<std::string> types;
  for (const auto& part : parts) types.push_back(part.type);
  // Own type first, then the structs it uses (FrameMarker uses Track, FrameBody uses Pose3) in
  // the order of idl/panoptes.idl.
  EXPECT_EQ(types, (std::vector<std::string>{"panoptes/msg/MocapFrame", "panoptes/msg/Pose3",
                                             "panoptes/msg/Track", "panoptes/msg/FrameMarker",
                                             "panoptes/msg/FrameBody", "panoptes/msg/FrameStages"}));
  for (const auto& part : parts) {
    const std::string name = part.type.substr(part.type.rfind('/') + 1);
    EXPECT_EQ(part.text.rfind("module panoptes {\nmodule msg {\n", 0), 0U) << part.type;
    EXPECT_NE(part.text.find("struct " + name + " {"), std::string::npos) << part.type;
    EXPECT_NE(part.text.find("};  // module msg\n};  // module panoptes\n"), std::string::npos) << part.type;
  }
  // References to other structs are written in full; the member names are not touched.
  EXPECT_NE(parts[0].text.find("panoptes::msg::FrameStages stages;"), std::string::npos);
  EXPECT_NE(parts[0].text.find("sequence<panoptes::msg::FrameBody> bodies;"), std::string::npos);
  EXPECT_NE(parts[3].text.find("panoptes::msg::Track state;"), std::string::npos);
  EXPECT_EQ(ros2idl_schema("panoptes/msg/MocapFrame"), schema);  // deterministic
}

TEST(Ros2IdlSchema, EveryRecordedTypeHasItsOwnSchema) {
  for (const auto& topic : dds::panoptes_raw_topics()) {
    const auto parts = sections(ros2idl_schema(topic.ros_type));
    ASSERT_FALSE(parts.empty()) << topic.ros_type;
    EXPECT_EQ(parts.front().type, topic.ros_type);
    std::set<std::string> unique;
    for (const auto& part : parts)
      EXPECT_TRUE(unique.insert(part.type).second) << topic.ros_type << ": " << part.type;
  }
  EXPECT_EQ(sections(ros2idl_schema("panoptes/msg/TimeSync")).size(), 1U);
  EXPECT_EQ(sections(ros2idl_schema("panoptes/msg/CameraInfo")).size(), 2U);  // and Pose3
}

// The ROS 2 types (idl/ros2.idl) under their ROS names, as rosidl's own .idl files have them.
TEST(Ros2IdlSchema, Ros2TypesAreWrittenUnderTheirRosNames) {
  const std::string schema = ros2idl_schema("tf2_msgs/msg/TFMessage");
  std::vector<std::string> types;
  for (const auto& part : sections(schema)) types.push_back(part.type);
  EXPECT_EQ(types, (std::vector<std::string>{"tf2_msgs/msg/TFMessage", "builtin_interfaces/msg/Time",
                                             "std_msgs/msg/Header", "geometry_msgs/msg/Vector3",
                                             "geometry_msgs/msg/Quaternion", "geometry_msgs/msg/Transform",
                                             "geometry_msgs/msg/TransformStamped"}));
  EXPECT_NE(schema.find("module tf2_msgs {\nmodule msg {\n@final\nstruct TFMessage {\n"
                        "  sequence<geometry_msgs::msg::TransformStamped> transforms;\n};\n"),
            std::string::npos)
      << schema;
  EXPECT_NE(schema.find("  builtin_interfaces::msg::Time stamp;"), std::string::npos);
  EXPECT_EQ(schema.find("dds_"), std::string::npos);
  EXPECT_EQ(sections(ros2idl_schema("mocap4r2_msgs/msg/Markers")).front().type, "mocap4r2_msgs/msg/Markers");
  EXPECT_EQ(sections(ros2idl_schema("geometry_msgs/msg/PoseStamped")).size(),
            6U);  // Time Header Point Quaternion Pose
}

TEST(Ros2IdlSchema, UnknownTypeIsAnError) {
  EXPECT_THROW(ros2idl_schema("panoptes/msg/NoSuchType"), std::invalid_argument);
  EXPECT_THROW(ros2idl_schema("geometry_msgs/msg/Polygon"), std::invalid_argument);
}

}  // namespace
}  // namespace panoptes::recorder
