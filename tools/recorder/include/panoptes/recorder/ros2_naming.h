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
// idl/panoptes.idl as it was at build time.
const char* panoptes_idl_text();
// The ros2idl schema of "panoptes/msg/<Type>": its struct and those it uses, from idl/panoptes.idl,
// inside their modules (the whole file for a type it does not define).
std::string ros2idl_schema(const std::string& ros_type);

}  // namespace panoptes::recorder
