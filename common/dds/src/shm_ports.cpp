// SPDX-License-Identifier: Apache-2.0
#include "panoptes/dds/shm_ports.h"

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

std::optional<int> participant_id_clear_of_owned_shm_ports(const ParticipantPortRule& rule,
                                                           std::uint32_t domain, int id_limit,
                                                           const std::filesystem::path& shm_dir) {
  const std::uint64_t domain_base =
      static_cast<std::uint64_t>(rule.base) + static_cast<std::uint64_t>(rule.domain_gain) * domain;
  for (int id = 0; id < id_limit; ++id) {
    const std::uint64_t participant_offset = static_cast<std::uint64_t>(rule.participant_gain) * id;
    const std::uint64_t metatraffic = domain_base + rule.metatraffic_unicast_offset + participant_offset;
    const std::uint64_t user = domain_base + rule.user_unicast_offset + participant_offset;
    if (metatraffic > kMaxPort || user > kMaxPort) return std::nullopt;
    if (!shm_port_owned(shm_dir, static_cast<std::uint32_t>(metatraffic)) &&
        !shm_port_owned(shm_dir, static_cast<std::uint32_t>(user)))
      return id;
  }
  return std::nullopt;
}

}  // namespace panoptes::dds
