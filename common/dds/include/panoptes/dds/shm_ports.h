// SPDX-License-Identifier: Apache-2.0
// Choosing a participant id whose shared-memory ports no participant owns, live or killed
// (docs/protocol.md, "Restarting after a crash"). Fast DDS 2.9 names a participant's shared-memory
// ports after its well-known UDP ports (RTPS 2.2 §9.6.1.1). A participant that takes the port of
// one killed with SIGKILL removes the dead one's segment ("zombie port") and creates a new one,
// while the writers in other processes keep writing into the removed segment they have mapped: the
// new participant then never receives their samples over shared memory. Choosing the id keeps the
// new participant off the killed one's ports.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>

namespace panoptes::dds {

// Fast DDS's well-known unicast ports: base + domain_gain * domain + offset + participant_gain * id.
struct ParticipantPortRule {
  std::uint32_t base = 7400;
  std::uint32_t domain_gain = 250;
  std::uint32_t participant_gain = 2;
  std::uint32_t metatraffic_unicast_offset = 10;
  std::uint32_t user_unicast_offset = 11;
};

// The file of shared-memory port `port` in `shm_dir` (Fast DDS 2.9: "fastrtps_port<port>").
std::filesystem::path shm_port_file(const std::filesystem::path& shm_dir, std::uint32_t port);

// Whether a participant owns shared-memory port `port`, or owned it and was killed: both the
// port's segment and its exclusive-reader lock file ("<segment>_el") exist. A participant that
// closes cleanly removes the lock file; a segment without one is reopened safely by the next.
bool shm_port_owned(const std::filesystem::path& shm_dir, std::uint32_t port);

// The shared-memory ports whose segment a process still maps although its file was removed
// ("fastrtps_port<N> (deleted)" in /proc/<pid>/maps): a killed participant's port that
// `fastdds shm clean` removed while writers mapped it. Only the processes this one may read
// (the same user, or root) are seen.
std::set<std::uint32_t> shm_ports_mapped_after_removal(const std::filesystem::path& proc_dir);

// The lowest participant id in [0, id_limit) none of whose unicast ports (metatraffic and user
// data) is owned (shm_port_owned) in `shm_dir` or in `removed_but_mapped`, and which this process
// has not used before (absent from `used_before`); if every such id was used before, the one used
// longest ago (the lowest value in `used_before`, an id -> order of use map); nullopt when every id
// is owned, or the ports would exceed 65535.
// Why not an id used before: Fast DDS 2.9 makes a participant's GUID from the process and the
// participant id (RTPSDomain::createParticipant); its own id choice never repeats one in a process.
// A participant that took the id of one this process closed had the closed one's GUID. A remote
// participant keeps the sequence number it last saw from each announcing GUID, and forgets it when
// the GUID's participant is removed, but not when it is removed because its lease expired (its
// goodbye lost: StatelessReader, RTPSReader::may_remove_history_record). Every later participant
// with that GUID starts again at announcement 1, which it ignores as seen: it is never found.
std::optional<int> participant_id_clear_of_owned_shm_ports(
    const ParticipantPortRule& rule, std::uint32_t domain, int id_limit, const std::filesystem::path& shm_dir,
    const std::set<std::uint32_t>& removed_but_mapped = {},
    const std::map<int, std::uint64_t>& used_before = {});

// The shared-memory segments whose lock file the process of `fd_dir` (/proc/self/fd) holds open:
// the data segments of the participants it created. Fast DDS 2.9 names a participant's segment
// "fastrtps_<16 hex digits>" and holds "<segment>_el" open (locked) while the participant lives.
std::set<std::string> shm_segments_held(const std::filesystem::path& fd_dir);

// Keeping a closed participant's segment reachable (docs/protocol.md, "Closing a participant"):
// Fast DDS 2.9.1 hands a receiver a reference to a sample in the sender's segment and the receiver
// opens that segment by name. A receiver that reaches such a reference after the sender closed
// (which removes the name) retries the same reference forever: every later sample to that
// receiver's port, from any participant, is lost (fixed in Fast DDS 2.12, eProsima/Fast-DDS#3992).
//
// keep_shm_segment_name: before the participant is deleted, a second name for its segment
// ("<segment>_keep" in `shm_dir`); false when there is nothing to keep.
bool keep_shm_segment_name(const std::filesystem::path& shm_dir, const std::string& segment);
// restore_shm_segment_name: after the deletion, the segment under its own name again (if the
// deletion removed it) and the second name gone. A receiver with a pending reference then reads
// it; Fast DDS removes the name once every receiver that opened it sees the owner gone (its lock
// file released, within 5 s), deploy/dds-shm-clean.sh otherwise. True when the name was restored.
bool restore_shm_segment_name(const std::filesystem::path& shm_dir, const std::string& segment);

}  // namespace panoptes::dds
