// SPDX-License-Identifier: Apache-2.0
#include "panoptes/dds/shm_ports.h"

#include <cctype>
#include <fstream>
#include <string_view>
#include <system_error>

namespace panoptes::dds {

namespace {

constexpr std::uint32_t kMaxPort = 65535;

bool file_exists(const std::filesystem::path& path) {
  std::error_code error;
  return std::filesystem::exists(path, error);
}

constexpr std::string_view kSegmentPrefix = "fastrtps_";
constexpr std::string_view kLockSuffix = "_el";
constexpr std::string_view kKeepSuffix = "_keep";

// "fastrtps_<16 hex digits>": a participant's data segment (not a port, "fastrtps_port<N>").
bool is_segment_name(std::string_view name) {
  if (!name.starts_with(kSegmentPrefix)) return false;
  const std::string_view id = name.substr(kSegmentPrefix.size());
  return id.size() == 16 && id.find_first_not_of("0123456789abcdef") == std::string_view::npos;
}

}  // namespace

std::filesystem::path shm_port_file(const std::filesystem::path& shm_dir, std::uint32_t port) {
  return shm_dir / ("fastrtps_port" + std::to_string(port));
}

bool shm_port_owned(const std::filesystem::path& shm_dir, std::uint32_t port) {
  const std::filesystem::path segment = shm_port_file(shm_dir, port);
  return file_exists(segment) && file_exists(segment.string() + "_el");
}

std::set<std::uint32_t> shm_ports_mapped_after_removal(const std::filesystem::path& proc_dir) {
  constexpr std::string_view kSegment = "/fastrtps_port";
  constexpr std::string_view kRemoved = " (deleted)";
  std::set<std::uint32_t> ports;
  std::error_code error;
  for (std::filesystem::directory_iterator it(proc_dir, error), end; !error && it != end;
       it.increment(error)) {
    const std::string pid = it->path().filename().string();
    if (pid.empty() || std::isdigit(static_cast<unsigned char>(pid.front())) == 0) continue;
    std::ifstream maps(it->path() / "maps");  // unreadable (another user's process): skipped
    std::string line;
    while (std::getline(maps, line)) {
      const std::size_t at = line.rfind(kSegment);
      if (at == std::string::npos || !line.ends_with(kRemoved)) continue;
      const std::size_t first = at + kSegment.size();
      const std::string_view digits =
          std::string_view(line).substr(first, line.size() - kRemoved.size() - first);
      if (digits.empty() || digits.size() > 5 ||
          digits.find_first_not_of("0123456789") != std::string_view::npos)
        continue;
      ports.insert(static_cast<std::uint32_t>(std::stoul(std::string(digits))));
    }
  }
  return ports;
}

std::optional<int> participant_id_clear_of_owned_shm_ports(const ParticipantPortRule& rule,
                                                           std::uint32_t domain, int id_limit,
                                                           const std::filesystem::path& shm_dir,
                                                           const std::set<std::uint32_t>& removed_but_mapped,
                                                           const std::map<int, std::uint64_t>& used_before) {
  const auto taken = [&](std::uint64_t port) {
    const auto port32 = static_cast<std::uint32_t>(port);
    return shm_port_owned(shm_dir, port32) || removed_but_mapped.count(port32) != 0;
  };
  const std::uint64_t domain_base =
      static_cast<std::uint64_t>(rule.base) + static_cast<std::uint64_t>(rule.domain_gain) * domain;
  std::optional<int> oldest;  // the clear id this process used longest ago
  std::uint64_t oldest_order = 0;
  for (int id = 0; id < id_limit; ++id) {
    const std::uint64_t participant_offset = static_cast<std::uint64_t>(rule.participant_gain) * id;
    const std::uint64_t metatraffic = domain_base + rule.metatraffic_unicast_offset + participant_offset;
    const std::uint64_t user = domain_base + rule.user_unicast_offset + participant_offset;
    if (metatraffic > kMaxPort || user > kMaxPort) break;
    if (taken(metatraffic) || taken(user)) continue;
    const auto used = used_before.find(id);
    if (used == used_before.end()) return id;
    if (!oldest || used->second < oldest_order) {
      oldest = id;
      oldest_order = used->second;
    }
  }
  return oldest;
}

std::set<std::string> shm_segments_held(const std::filesystem::path& fd_dir) {
  std::set<std::string> segments;
  std::error_code error;
  for (std::filesystem::directory_iterator it(fd_dir, error), end; !error && it != end; it.increment(error)) {
    std::error_code link_error;
    const std::filesystem::path target = std::filesystem::read_symlink(it->path(), link_error);
    if (link_error) continue;  // closed since listed, or not a link
    const std::string name = target.filename().string();
    if (!name.ends_with(kLockSuffix)) continue;
    const std::string segment = name.substr(0, name.size() - kLockSuffix.size());
    if (is_segment_name(segment)) segments.insert(segment);
  }
  return segments;
}

bool keep_shm_segment_name(const std::filesystem::path& shm_dir, const std::string& segment) {
  if (!is_segment_name(segment)) return false;
  const std::filesystem::path keep = shm_dir / (segment + std::string(kKeepSuffix));
  std::error_code error;
  std::filesystem::remove(keep, error);  // left by a process killed while closing
  std::filesystem::create_hard_link(shm_dir / segment, keep, error);
  return !error;
}

bool restore_shm_segment_name(const std::filesystem::path& shm_dir, const std::string& segment) {
  const std::filesystem::path keep = shm_dir / (segment + std::string(kKeepSuffix));
  std::error_code error;
  if (file_exists(shm_dir / segment)) {  // not removed (or created again): the second name goes
    std::filesystem::remove(keep, error);
    return false;
  }
  std::filesystem::rename(keep, shm_dir / segment, error);
  if (!error) return true;
  std::filesystem::remove(keep, error);  // nothing kept (keep_shm_segment_name failed)
  return false;
}

}  // namespace panoptes::dds
