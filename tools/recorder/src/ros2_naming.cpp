// SPDX-License-Identifier: Apache-2.0
#include "panoptes/recorder/ros2_naming.h"

#include <algorithm>
#include <cctype>
#include <map>
#include <set>
#include <sstream>
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

struct Definition {
  std::size_t order = 0;
  std::string text;                   // annotations, "struct Name {" ... "};"
  std::set<std::string> identifiers;  // every word of the body
};

// The structs of module panoptes::msg in idl/panoptes.idl, by name.
std::map<std::string, Definition> idl_structs(const std::string& idl) {
  std::map<std::string, Definition> structs;
  std::istringstream lines(idl);
  std::string line;
  std::string annotations;
  Definition* open = nullptr;
  while (std::getline(lines, line)) {
    if (open != nullptr) {
      open->text += line + "\n";
      std::string word;
      for (const char ch : line + " ") {
        if (std::isalnum(static_cast<unsigned char>(ch)) != 0 || ch == '_') {
          word += ch;
        } else if (!word.empty()) {
          open->identifiers.insert(word);
          word.clear();
        }
      }
      if (line.rfind("};", 0) == 0) open = nullptr;
      continue;
    }
    if (line.rfind('@', 0) == 0) {
      annotations += line + "\n";
    } else if (line.rfind("struct ", 0) == 0) {
      std::istringstream words(line.substr(7));
      std::string name;
      words >> name;
      open = &structs[name];
      open->order = structs.size();
      open->text = annotations + line + "\n";
      annotations.clear();
    } else if (!line.empty() && line.rfind("//", 0) != 0) {
      annotations.clear();
    }
  }
  return structs;
}

}  // namespace

std::string ros2idl_schema(const std::string& ros_type) {
  const std::string prefix = "panoptes/msg/";
  const auto structs = idl_structs(panoptes_idl_text());
  const std::string name = ros_type.rfind(prefix, 0) == 0 ? ros_type.substr(prefix.size()) : ros_type;
  if (structs.count(name) == 0) return panoptes_idl_text();
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
  std::vector<const Definition*> ordered;
  ordered.reserve(needed.size());
  for (const auto& each : needed) ordered.push_back(&structs.at(each));
  std::sort(ordered.begin(), ordered.end(), [](const auto* a, const auto* b) { return a->order < b->order; });
  std::string text = "module panoptes {\nmodule msg {\n\n";
  for (const auto* definition : ordered) text += definition->text + "\n";
  return text + "};  // module msg\n};  // module panoptes\n";
}

}  // namespace panoptes::recorder
