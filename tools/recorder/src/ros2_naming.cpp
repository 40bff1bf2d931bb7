// SPDX-License-Identifier: Apache-2.0
#include "panoptes/recorder/ros2_naming.h"

#include <algorithm>
#include <cctype>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace panoptes::recorder {

std::string ros_topic_name(const std::string& dds_topic) {
  if (dds_topic.rfind("rt/", 0) == 0) return dds_topic.substr(2);
  return "/" + dds_topic;
}

std::optional<std::string> dds_topic_name(const std::string& ros_topic) {
  if (ros_topic.empty() || ros_topic.front() != '/') return std::nullopt;
  return "rt" + ros_topic;
}

namespace {

constexpr const char* kPackagePrefix = "panoptes/msg/";
constexpr const char* kScope = "panoptes::msg::";

struct Definition {
  std::size_t order = 0;
  std::vector<std::string> lines;     // annotations, "struct Name {" ... "};"
  std::set<std::string> identifiers;  // every word of the body's code (comments left out)
};

bool is_word_char(char ch) {
  return std::isalnum(static_cast<unsigned char>(ch)) != 0 || ch == '_';
}

// The words of a line's code, before any "//" comment.
std::vector<std::string> code_words(const std::string& line) {
  std::vector<std::string> words;
  std::string word;
  for (const char ch : line.substr(0, line.find("//")) + " ") {
    if (is_word_char(ch)) {
      word += ch;
    } else if (!word.empty()) {
      words.push_back(word);
      word.clear();
    }
  }
  return words;
}

// The structs of module panoptes::msg in idl/panoptes.idl, by name.
std::map<std::string, Definition> idl_structs(const std::string& idl) {
  std::map<std::string, Definition> structs;
  std::istringstream lines(idl);
  std::string line;
  std::vector<std::string> annotations;
  Definition* open = nullptr;
  while (std::getline(lines, line)) {
    if (open != nullptr) {
      open->lines.push_back(line);
      for (auto& word : code_words(line)) open->identifiers.insert(std::move(word));
      if (line.rfind("};", 0) == 0) open = nullptr;
      continue;
    }
    if (line.rfind('@', 0) == 0) {
      annotations.push_back(line);
    } else if (line.rfind("struct ", 0) == 0) {
      std::istringstream words(line.substr(7));
      std::string name;
      words >> name;
      open = &structs[name];
      open->order = structs.size();
      open->lines = annotations;
      open->lines.push_back(line);
      annotations.clear();
    } else if (!line.empty() && line.rfind("//", 0) != 0) {
      annotations.clear();
    }
  }
  return structs;
}

// A body line with every reference to another struct of the module written in full
// ("Pose3 pose;" -> "panoptes::msg::Pose3 pose;"), as rosidl writes them; comments unchanged.
std::string qualified(const std::string& line, const std::map<std::string, Definition>& structs) {
  const std::size_t comment = std::min(line.find("//"), line.size());
  std::string out;
  std::size_t i = 0;
  while (i < comment) {
    if (!is_word_char(line[i])) {
      out += line[i++];
      continue;
    }
    std::size_t end = i;
    while (end < comment && is_word_char(line[end])) ++end;
    const std::string word = line.substr(i, end - i);
    const bool scoped = i >= 2 && line.compare(i - 2, 2, "::") == 0;
    if (!scoped && structs.count(word) != 0) out += kScope;
    out += word;
    i = end;
  }
  return out + line.substr(comment);
}

// The dependencies of `name`, transitively, in the order idl/panoptes.idl defines them.
std::vector<std::string> dependencies(const std::string& name,
                                      const std::map<std::string, Definition>& structs) {
  std::set<std::string> needed;
  std::vector<std::string> todo{name};
  while (!todo.empty()) {
    const std::string next = todo.back();
    todo.pop_back();
    if (!needed.insert(next).second) continue;
    for (const auto& word : structs.at(next).identifiers) {
      if (word != next && structs.count(word) != 0) todo.push_back(word);
    }
  }
  needed.erase(name);
  std::vector<std::string> ordered(needed.begin(), needed.end());
  std::sort(ordered.begin(), ordered.end(),
            [&](const auto& a, const auto& b) { return structs.at(a).order < structs.at(b).order; });
  return ordered;
}

// One section of a ros2idl schema: the delimiter, then the struct inside its modules.
std::string idl_section(const std::string& name, const std::map<std::string, Definition>& structs) {
  std::string text =
      std::string(80, '=') + "\nIDL: " + kPackagePrefix + name + "\nmodule panoptes {\nmodule msg {\n";
  for (const auto& line : structs.at(name).lines) {
    // The struct's own line keeps its short name; its members name other structs in full.
    text += (line.rfind("struct ", 0) == 0 ? line : qualified(line, structs)) + "\n";
  }
  return text + "};  // module msg\n};  // module panoptes\n";
}

// --- the ROS 2 types of idl/ros2.idl ----------------------------------------------------------

struct RosStruct {
  std::size_t order = 0;
  std::string package;
  std::vector<std::string> lines;  // annotations, "struct Name {" ... "};", in ROS naming
  std::set<std::string> uses;      // the ROS types its members name ("geometry_msgs/msg/Point")
};

const std::regex& wire_name() {
  static const std::regex pattern(R"((\w+)::msg::dds_::(\w+)_\b)");
  return pattern;
}

// "geometry_msgs::msg::dds_::Point_" -> "geometry_msgs::msg::Point" in a line of idl/ros2.idl.
std::string ros_naming(const std::string& line) {
  return std::regex_replace(line, wire_name(), "$1::msg::$2");
}

// The structs of idl/ros2.idl by ROS type ("tf2_msgs/msg/TFMessage").
std::map<std::string, RosStruct> ros2_structs(const std::string& idl) {
  std::map<std::string, RosStruct> structs;
  std::istringstream lines(idl);
  std::string line, package;
  std::vector<std::string> annotations;
  RosStruct* open = nullptr;
  while (std::getline(lines, line)) {
    if (open != nullptr) {
      open->lines.push_back(ros_naming(line));
      const std::string code = line.substr(0, line.find("//"));
      for (std::sregex_iterator it(code.begin(), code.end(), wire_name()), end; it != end; ++it)
        open->uses.insert((*it)[1].str() + "/msg/" + (*it)[2].str());
      if (line.rfind("};", 0) == 0) open = nullptr;
    } else if (line.rfind("module ", 0) == 0) {
      std::istringstream words(line.substr(7));
      words >> package;
    } else if (line.rfind('@', 0) == 0) {
      annotations.push_back(line);
    } else if (line.rfind("struct ", 0) == 0) {
      std::istringstream words(line.substr(7));
      std::string name;
      words >> name;
      if (!name.empty() && name.back() == '_') name.pop_back();
      std::string type = package;
      type.append("/msg/").append(name);
      open = &structs[type];
      open->order = structs.size();
      open->package = package;
      open->lines = annotations;
      open->lines.push_back("struct " + name + " {");
      annotations.clear();
    } else if (!line.empty() && line.rfind("//", 0) != 0) {
      annotations.clear();
    }
  }
  return structs;
}

std::string ros2_section(const std::string& type, const RosStruct& s) {
  std::string text = std::string(80, '=') + "\nIDL: " + type + "\nmodule " + s.package + " {\nmodule msg {\n";
  for (const auto& line : s.lines) text += line + "\n";
  return text + "};  // module msg\n};  // module " + s.package + "\n";
}

std::string ros2_types_schema(const std::string& ros_type) {
  const auto structs = ros2_structs(ros2_idl_text());
  if (structs.count(ros_type) == 0) return "";
  std::set<std::string> needed;
  std::vector<std::string> todo{ros_type};
  while (!todo.empty()) {
    const std::string next = todo.back();
    todo.pop_back();
    if (!needed.insert(next).second) continue;
    for (const auto& used : structs.at(next).uses) todo.push_back(used);
  }
  needed.erase(ros_type);
  std::vector<std::string> ordered(needed.begin(), needed.end());
  std::sort(ordered.begin(), ordered.end(),
            [&](const auto& a, const auto& b) { return structs.at(a).order < structs.at(b).order; });
  std::string text = ros2_section(ros_type, structs.at(ros_type));
  for (const auto& type : ordered) text += ros2_section(type, structs.at(type));
  return text;
}

}  // namespace

std::string ros2idl_schema(const std::string& ros_type) {
  const auto structs = idl_structs(panoptes_idl_text());
  const std::string prefix = kPackagePrefix;
  const std::string name = ros_type.rfind(prefix, 0) == 0 ? ros_type.substr(prefix.size()) : "";
  if (structs.count(name) == 0) {
    if (auto ros = ros2_types_schema(ros_type); !ros.empty()) return ros;
    throw std::invalid_argument("ros2idl_schema: " + ros_type +
                                " is not a type of idl/panoptes.idl nor idl/ros2.idl");
  }
  std::string text = idl_section(name, structs);
  for (const auto& dependency : dependencies(name, structs)) text += idl_section(dependency, structs);
  return text;
}

}  // namespace panoptes::recorder
