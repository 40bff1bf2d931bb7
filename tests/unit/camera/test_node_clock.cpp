// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <optional>
#include <stdexcept>
#include <string>

#include "panoptes/camera/node_clock.h"
#include "panoptes/time.h"

namespace panoptes::camera {
namespace {

std::string skew_error(const std::string& text) {
  try {
    parse_clock_skew(text);
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "";
}

TEST(ClockSkewParsing, ReadsOffsetInMillisecondsAndDriftInPpm) {
  const ClockSkew skew = parse_clock_skew("12.5,-40");
  EXPECT_EQ(skew.offset_ns, 12'500'000);
  EXPECT_DOUBLE_EQ(skew.drift_ppm, -40.0);
  const ClockSkew none = parse_clock_skew("");
  EXPECT_EQ(none.offset_ns, 0);
  EXPECT_EQ(none.drift_ppm, 0.0);
}

TEST(ClockSkewParsing, BadTextNamesTheOptionAndWhatIsWrong) {
  EXPECT_EQ(skew_error("5"), "--clock-skew '5': no comma (expected <offset_ms>,<drift_ppm>)");
  EXPECT_NE(skew_error("abc,2").find("not two numbers"), std::string::npos);
  EXPECT_NE(skew_error(",2").find("not two numbers"), std::string::npos);
  EXPECT_NE(skew_error("1x,2").find("offset is not a number"), std::string::npos);
  EXPECT_NE(skew_error("1,2y").find("drift is not a number"), std::string::npos);
  EXPECT_NE(skew_error("3600001,0").find("offset beyond"), std::string::npos);
  EXPECT_NE(skew_error("0,10001").find("drift beyond"), std::string::npos);
  EXPECT_NE(skew_error("nan,0").find("offset beyond"), std::string::npos);
  EXPECT_EQ(skew_error("-3600000,10000"), "");
}

TEST(NodeClock, WithoutOffsetOrSkewIsTheIdentity) {
  const NodeClock clock;
  EXPECT_FALSE(clock.skewed());
  EXPECT_EQ(clock.from_wall(1'700'000'000'123'456'789), 1'700'000'000'123'456'789);
  EXPECT_EQ(clock.from_source(42), 42);
}

TEST(NodeClock, SkewAddsOffsetAndDriftSinceStart) {
  const TimeNs start = 1'000 * kNsPerSecond;
  const NodeClock clock(start, 0, ClockSkew{5 * kNsPerMillisecond, 100.0});
  EXPECT_TRUE(clock.skewed());
  EXPECT_DOUBLE_EQ(clock.drift_ppm(), 100.0);
  EXPECT_EQ(clock.from_wall(start), start + 5'000'000);
  // 10 s later: 100 ppm of 10 s = 1 ms more.
  EXPECT_EQ(clock.from_wall(start + 10 * kNsPerSecond), start + 10 * kNsPerSecond + 6'000'000);
}

TEST(NodeClock, SourceStampsCarryTheSourceOffsetAndGetTheSkewOfTheirWallTime) {
  const TimeNs start = 1'000 * kNsPerSecond;
  const TimeNs source_offset = 300 * kNsPerMillisecond;
  const NodeClock clock(start, source_offset, ClockSkew{0, 1000.0});
  const TimeNs wall = start + 2 * kNsPerSecond;
  // The source stamped the frame on wall + its offset; the node's clock at that wall time is
  // the same stamp plus the drift of 2 s (2 ms at 1000 ppm), exactly what from_wall gives.
  EXPECT_EQ(clock.from_source(wall + source_offset), clock.from_wall(wall));
  EXPECT_EQ(clock.from_wall(wall), wall + source_offset + 2'000'000);
}

class FixedOffsetSync final : public ClockSyncView {
 public:
  bool synced = false;
  TimeNs offset_ns = 0;
  bool synchronised() const override { return synced; }
  ClockEstimate estimate() const override { return {}; }
  std::optional<TimeNs> to_server(TimeNs local_ns) const override {
    if (!synced) return std::nullopt;
    return local_ns - offset_ns;
  }
};

TEST(StampCorrection, LocalStampsPassUntilSynchronisedThenMoveToTheCommonBase) {
  const NodeClock clock;
  const StampCorrection unsynchronisable(clock, nullptr);
  EXPECT_EQ(unsynchronisable.to_common(100), 100);
  FixedOffsetSync sync;
  sync.offset_ns = 30;
  const StampCorrection stamps(clock, &sync);
  EXPECT_EQ(stamps.to_common(100), 100);
  sync.synced = true;
  EXPECT_EQ(stamps.to_common(100), 70);
}

}  // namespace
}  // namespace panoptes::camera
