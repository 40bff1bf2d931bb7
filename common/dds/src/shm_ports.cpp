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

}  // namespace panoptes::dds
