// SPDX-License-Identifier: Apache-2.0
// How a recording names what it holds, as rosbag2 does with the MCAP ros2 profile: DDS topic
// "rt/panoptes/features" is ROS 2 topic "/panoptes/features"; type panoptes::msg::FeatureFrame is
// schema "panoptes/msg/FeatureFrame" in encoding "ros2idl" with its definitions from idl/panoptes.idl.
#pragma once

#include <optional>
#include <string>

namespace panoptes::recorder {

inline constexpr const char* kSchemaEncoding = "ros2idl";
inline constexpr const char* kMessageEncoding = "cdr";

std::string ros_topic_name(const std::string& dds_topic);
// "/panoptes/features" -> "rt/panoptes/features"; nullopt for a name without the leading '/'.
std::optional<std::string> dds_topic_name(const std::string& ros_topic);
// idl/panoptes.idl and idl/ros2.idl as they were at build time.
const char* panoptes_idl_text();
const char* ros2_idl_text();
// The ros2idl schema of "panoptes/msg/<Type>" as rosbag2's message-definition encoding has it: one
// section per struct, the type's own first, then every struct it uses (transitively) in the order of
// idl/panoptes.idl. Each section is a line of 80 '=', a line "IDL: panoptes/msg/<Name>", and the
// struct inside "module panoptes { module msg { ... }; };" with references to other structs written
// in full (panoptes::msg::Pose3). Readers such as Foxglove decode with the first section's struct.
// The ROS 2 types of idl/ros2.idl ("tf2_msgs/msg/TFMessage", "geometry_msgs/msg/PoseStamped", ...)
// likewise, under their ROS names: "IDL: tf2_msgs/msg/TFMessage", "module tf2_msgs { module msg {
// struct TFMessage {...}", references as geometry_msgs::msg::TransformStamped (the wire's dds_
// module and trailing '_' taken away, as rosidl's own .idl files name them).
// Throws std::invalid_argument for a type neither file defines.
std::string ros2idl_schema(const std::string& ros_type);

}  // namespace panoptes::recorder
