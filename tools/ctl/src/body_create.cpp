// SPDX-License-Identifier: Apache-2.0
#include "panoptes/ctl_actions/body_create.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <system_error>
#include <thread>
#include <utility>

#include <yaml-cpp/yaml.h>

#include "panoptes/calibration_file.h"
#include "panoptes/errors.h"
#include "panoptes/estimator/body_identification.h"

namespace panoptes::ctl {
namespace {

std::string id_list(const std::vector<std::int64_t>& ids) {
  std::ostringstream out;
  for (std::size_t i = 0; i < ids.size(); ++i) out << (i ? "," : "") << ids[i];
  return ids.empty() ? "none" : out.str();
}

std::vector<std::int64_t> seen_ids(const TrackPositions& seen) {
  std::vector<std::int64_t> ids;
  for (const auto& [id, position] : seen) ids.push_back(id);
  return ids;
}

std::vector<std::int64_t> tracks_near(const BodyRequest& request, const TrackPositions& seen) {
  std::vector<std::pair<double, std::int64_t>> within;
  for (const auto& [id, position] : seen) {
    const double distance = (position - *request.near).norm();
    if (distance <= request.radius_m) within.emplace_back(distance, id);
  }
  std::sort(within.begin(), within.end());
  std::vector<std::int64_t> ids;
  ids.reserve(within.size());
  for (const auto& [distance, id] : within) ids.push_back(id);
  return ids;
}

// An exclusive lock on `<file>.lock` (flock: released when its holder ends, even killed), held
// while the bodies file is read, appended and replaced: two creations at once (the CLI and a
// console, or two consoles) each keep their body. Waits up to 10 s for another writer.
class BodiesFileLock {
 public:
  explicit BodiesFileLock(const std::filesystem::path& bodies_file) {
    const std::string path = bodies_file.string() + ".lock";
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0)
      throw ConfigError(path, "", std::string("cannot open the lock file: ") + std::strerror(errno));
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      const int error = errno;
      if ((error != EWOULDBLOCK && error != EINTR) || std::chrono::steady_clock::now() > give_up) {
        ::close(fd_);
        throw ConfigError(path, "",
                          "cannot lock the bodies file: " +
                              (error == EWOULDBLOCK ? std::string("another writer held it for 10 s")
                                                    : std::string(std::strerror(error))));
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  ~BodiesFileLock() { ::close(fd_); }  // closing releases the lock
  BodiesFileLock(const BodiesFileLock&) = delete;
  BodiesFileLock& operator=(const BodiesFileLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace

std::vector<std::int64_t> select_tracks(const BodyRequest& request, const TrackPositions& seen) {
  const std::string key = request.near ? "--near" : "--tracks";
  std::vector<std::int64_t> ids = request.near ? tracks_near(request, seen) : request.tracks;
  std::vector<std::int64_t> missing;
  std::set<std::int64_t> unique;
  for (const std::int64_t id : ids) {
    if (!unique.insert(id).second)
      throw ConfigError("body '" + request.name + "'", key,
                        "track " + std::to_string(id) + " is given twice");
    if (seen.count(id) == 0) missing.push_back(id);
  }
  if (!missing.empty())
    throw ConfigError("body '" + request.name + "'", key,
                      "no confirmed track " + id_list(missing) +
                          " on the bus (tracks seen: " + id_list(seen_ids(seen)) + ")");
  if (ids.size() < 3)
    throw ConfigError("body '" + request.name + "'", key,
                      "a rigid body needs at least 3 markers, got " + std::to_string(ids.size()) + " (" +
                          id_list(ids) + "; tracks seen: " + id_list(seen_ids(seen)) + ")");
  if (request.pivot && unique.count(*request.pivot) == 0)
    throw ConfigError(
        "body '" + request.name + "'", "--pivot",
        "track " + std::to_string(*request.pivot) + " is not one of the body's (" + id_list(ids) + ")");
  return ids;
}

BodyDefinition make_body(const BodyRequest& request, const std::vector<std::int64_t>& ids,
                         const TrackPositions& seen) {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  for (const std::int64_t id : ids) origin += seen.at(id);
  origin /= static_cast<double>(ids.size());
  if (request.pivot) origin = seen.at(*request.pivot);
  BodyDefinition body;
  body.name = request.name;
  for (const std::int64_t id : ids) body.markers.push_back(seen.at(id) - origin);
  estimator::validate_body(body, "body '" + request.name + "' from tracks " + id_list(ids));
  return body;
}

namespace {
// The bodies file's root (an empty map when the file does not exist yet); ConfigError when it is
// not a bodies file or already defines `name`.
YAML::Node bodies_root(const std::filesystem::path& bodies_file, const std::string& name) {
  const std::string file = bodies_file.string();
  YAML::Node root;
  std::error_code error;
  if (std::filesystem::exists(bodies_file, error)) {
    try {
      root = YAML::LoadFile(file);
    } catch (const YAML::Exception& e) {
      throw ConfigError(file, "", std::string("not YAML: ") + e.what());
    }
  }
  if (!root.IsDefined() || root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
  if (!root.IsMap()) throw ConfigError(file, "", "not a bodies file (a map with a 'bodies' list)");
  YAML::Node list = root["bodies"];
  if (list.IsDefined() && !list.IsNull() && !list.IsSequence())
    throw ConfigError(file, "bodies", "not a list");
  for (const auto& entry : list)
    if (entry["name"] && entry["name"].as<std::string>() == name)
      throw ConfigError(file, "bodies", "a body named '" + name + "' is already defined");
  return root;
}
}  // namespace

void check_body_name(const std::filesystem::path& bodies_file, const std::string& name) {
  (void)bodies_root(bodies_file, name);
}

void append_body(const std::filesystem::path& bodies_file, const BodyDefinition& body) {
  const std::string file = bodies_file.string();
  const BodiesFileLock lock(bodies_file);
  YAML::Node root = bodies_root(bodies_file, body.name);
  std::error_code error;
  YAML::Node entry(YAML::NodeType::Map);
  entry["name"] = body.name;
  for (const Eigen::Vector3d& marker : body.markers) {
    YAML::Node point(YAML::NodeType::Sequence);
    point.SetStyle(YAML::EmitterStyle::Flow);
    for (int i = 0; i < 3; ++i) point.push_back(marker[i]);
    entry["markers"].push_back(point);
  }
  root["bodies"].push_back(entry);
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << root;
  const std::filesystem::path temporary = bodies_file.string() + ".new";
  {
    std::ofstream stream(temporary);
    stream << out.c_str() << "\n";
    if (!stream) throw ConfigError(temporary.string(), "", "cannot write");
  }
  try {
    (void)load_bodies(temporary);  // what the estimator will read: a file it refuses is not installed
  } catch (...) {
    std::filesystem::remove(temporary, error);
    throw;
  }
  std::filesystem::rename(temporary, bodies_file, error);
  if (error) throw ConfigError(file, "", "cannot replace it: " + error.message());
}

}  // namespace panoptes::ctl
