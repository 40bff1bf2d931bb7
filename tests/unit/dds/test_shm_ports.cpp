// SPDX-License-Identifier: Apache-2.0
// The participant id a bus takes on a host where participants were killed (shm_ports.h): never one
// whose shared-memory port a live or killed participant owns, the first free one otherwise.
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "panoptes/dds/shm_ports.h"

namespace panoptes::dds {
namespace {

class ShmPortsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("panoptes-shm-ports-" + std::to_string(getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  static void touch(const std::filesystem::path& path) { std::ofstream file(path); }
  // A port as a participant leaves it: its segment, and the reader lock file unless it closed cleanly.
  void leave_port(std::uint32_t port, bool lock_file) const {
    std::ofstream(shm_port_file(dir_, port)) << "segment";
    if (lock_file) touch(shm_port_file(dir_, port).string() + "_el");
  }
  // Domain 3's user-data port of participant `id` with Fast DDS's default port rule.
  static std::uint32_t user_port(int id) { return 7400 + 250 * 3 + 11 + 2 * id; }
  static std::uint32_t metatraffic_port(int id) { return 7400 + 250 * 3 + 10 + 2 * id; }

  std::filesystem::path dir_;
  ParticipantPortRule rule_;
};

TEST_F(ShmPortsTest, EmptyHostGivesTheFirstId) {
  EXPECT_EQ(participant_id_clear_of_owned_shm_ports(rule_, 3, 80, dir_), std::optional<int>(0));
}

TEST_F(ShmPortsTest, SkipsPortsOfLiveAndKilledParticipants) {
  // Ids 0 and 1 live or killed (segment and lock file); id 2 closed cleanly (no lock file): its
  // segment is reopened by the next participant as Fast DDS does, nobody is cut off.
  leave_port(user_port(0), true);
  leave_port(user_port(1), true);
  leave_port(user_port(2), false);
  EXPECT_TRUE(shm_port_owned(dir_, user_port(0)));
  EXPECT_FALSE(shm_port_owned(dir_, user_port(2)));
  EXPECT_EQ(participant_id_clear_of_owned_shm_ports(rule_, 3, 80, dir_), std::optional<int>(2));
}

TEST_F(ShmPortsTest, ALockFileWithoutItsSegmentDoesNotHoldTheId) {
  // deploy/dds-shm-clean.sh removes segments no process maps and leaves the lock files.
  touch(shm_port_file(dir_, user_port(0)).string() + "_el");
  EXPECT_EQ(participant_id_clear_of_owned_shm_ports(rule_, 3, 80, dir_), std::optional<int>(0));
}

TEST_F(ShmPortsTest, SkipsAnIdWhoseMetatrafficPortIsOwned) {
  // Profiles without a metatraffic locator list (lan.xml) also discover over shared memory.
  leave_port(metatraffic_port(0), true);
  EXPECT_EQ(participant_id_clear_of_owned_shm_ports(rule_, 3, 80, dir_), std::optional<int>(1));
}

TEST_F(ShmPortsTest, NoIdWhenEveryIdInTheRangeIsOwned) {
  for (int id = 0; id < 4; ++id) leave_port(user_port(id), true);
  EXPECT_EQ(participant_id_clear_of_owned_shm_ports(rule_, 3, 4, dir_), std::nullopt);
  EXPECT_EQ(participant_id_clear_of_owned_shm_ports(rule_, 3, 5, dir_), std::optional<int>(4));
}

TEST_F(ShmPortsTest, NoIdBeyondTheLastPort) {
  // Domain 232: 7400 + 58000 + 11 = 65411, so participant 62 is the last with ports below 65536.
  EXPECT_EQ(participant_id_clear_of_owned_shm_ports(rule_, 232, 80, dir_), std::optional<int>(0));
  for (int id = 0; id <= 62; ++id) leave_port(7400 + 250 * 232 + 11 + 2 * id, true);
  EXPECT_EQ(participant_id_clear_of_owned_shm_ports(rule_, 232, 80, dir_), std::nullopt);
}

TEST_F(ShmPortsTest, SkipsAPortRemovedWhileAProcessMapsIt) {
  // `fastdds shm clean` removed a killed participant's port 0 while a camera maps it: no file is
  // left, only the camera's mapping, and the next participant there would be cut off from it.
  const std::filesystem::path proc = dir_ / "proc";
  std::filesystem::create_directories(proc / "4242");
  std::filesystem::create_directories(proc / "self-not-a-pid");
  std::ofstream(proc / "4242" / "maps")
      << "7f0000000000-7f0000001000 rw-s 00000000 00:1a 17 /dev/shm/fastrtps_port" << user_port(0)
      << " (deleted)\n"
      << "7f0000001000-7f0000002000 rw-s 00000000 00:1a 18 /dev/shm/fastrtps_port" << user_port(1) << "\n"
      << "7f0000002000-7f0000003000 rw-s 00000000 00:1a 19 /dev/shm/fastrtps_7416c84d46971cd5 (deleted)\n";
  const std::set<std::uint32_t> removed = shm_ports_mapped_after_removal(proc);
  EXPECT_EQ(removed, std::set<std::uint32_t>{user_port(0)});
  EXPECT_EQ(participant_id_clear_of_owned_shm_ports(rule_, 3, 80, dir_, removed), std::optional<int>(1));
  EXPECT_TRUE(shm_ports_mapped_after_removal(dir_ / "no-such-proc").empty());
}

TEST_F(ShmPortsTest, AnIdThisProcessUsedBeforeIsTakenLastTheOldestFirst) {
  // Ids 0 and 1 were used by this process (0 first): a new participant takes 2, not the GUID of a
  // closed one (shm_ports.h).
  const std::map<int, std::uint64_t> used{{0, 1}, {1, 2}};
  EXPECT_EQ(participant_id_clear_of_owned_shm_ports(rule_, 3, 80, dir_, {}, used), std::optional<int>(2));
  // Only ids used before are clear: the one used longest ago.
  EXPECT_EQ(participant_id_clear_of_owned_shm_ports(rule_, 3, 2, dir_, {}, used), std::optional<int>(0));
  EXPECT_EQ(participant_id_clear_of_owned_shm_ports(rule_, 3, 2, dir_, {}, {{0, 5}, {1, 2}}),
            std::optional<int>(1));
  // An id owned by a live participant stays out, used before or not.
  leave_port(user_port(2), true);
  EXPECT_EQ(participant_id_clear_of_owned_shm_ports(rule_, 3, 3, dir_, {}, used), std::optional<int>(0));
  EXPECT_EQ(participant_id_clear_of_owned_shm_ports(rule_, 3, 80, dir_, {}, used), std::optional<int>(3));
}

// The segments a process created, from its open file descriptors: the lock files of segments,
// not of ports, nor any other file.
TEST_F(ShmPortsTest, SegmentsHeldAreTheSegmentLockFilesOpen) {
  const std::filesystem::path fds = dir_ / "fd";
  std::filesystem::create_directories(fds);
  std::filesystem::create_symlink("/dev/shm/fastrtps_0123456789abcdef_el", fds / "3");
  std::filesystem::create_symlink("/dev/shm/fastrtps_fedcba9876543210_el", fds / "4");
  std::filesystem::create_symlink("/dev/shm/fastrtps_port7411_el", fds / "5");       // a port's
  std::filesystem::create_symlink("/dev/shm/fastrtps_0123456789abcdef", fds / "6");  // mapped, not locked
  std::filesystem::create_symlink("/dev/shm/fastrtps_0123_el", fds / "7");           // not a segment id
  std::filesystem::create_symlink("socket:[12345]", fds / "8");
  touch(fds / "9");  // not a link
  EXPECT_EQ(shm_segments_held(fds),
            (std::set<std::string>{"fastrtps_0123456789abcdef", "fastrtps_fedcba9876543210"}));
  EXPECT_TRUE(shm_segments_held(dir_ / "absent").empty());
}

// Closing a participant removes its segment's name while receivers may hold references into it
// (shm_ports.h): the name comes back, with the same contents, and the second name goes.
TEST_F(ShmPortsTest, AClosedParticipantsSegmentNameIsRestored) {
  const std::string segment = "fastrtps_00112233445566aa";
  std::ofstream(dir_ / segment) << "samples";
  ASSERT_TRUE(keep_shm_segment_name(dir_, segment));
  EXPECT_TRUE(std::filesystem::exists(dir_ / (segment + "_keep")));
  std::filesystem::remove(dir_ / segment);  // what Fast DDS does as the participant closes
  EXPECT_TRUE(restore_shm_segment_name(dir_, segment));
  std::ifstream restored(dir_ / segment);
  std::string contents;
  restored >> contents;
  EXPECT_EQ(contents, "samples");
  EXPECT_FALSE(std::filesystem::exists(dir_ / (segment + "_keep")));
}

TEST_F(ShmPortsTest, ASegmentNameStillThereIsLeftAndTheSecondNameGoes) {
  const std::string segment = "fastrtps_00112233445566bb";
  std::ofstream(dir_ / segment) << "samples";
  ASSERT_TRUE(keep_shm_segment_name(dir_, segment));
  EXPECT_FALSE(restore_shm_segment_name(dir_, segment));
  EXPECT_TRUE(std::filesystem::exists(dir_ / segment));
  EXPECT_FALSE(std::filesystem::exists(dir_ / (segment + "_keep")));
}

TEST_F(ShmPortsTest, NothingIsKeptOfAMissingSegmentOrAPort) {
  EXPECT_FALSE(keep_shm_segment_name(dir_, "fastrtps_00112233445566cc"));  // no such file
  leave_port(7411, true);
  EXPECT_FALSE(keep_shm_segment_name(dir_, "fastrtps_port7411"));
  EXPECT_FALSE(restore_shm_segment_name(dir_, "fastrtps_00112233445566cc"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "fastrtps_00112233445566cc"));
}

}  // namespace
}  // namespace panoptes::dds
