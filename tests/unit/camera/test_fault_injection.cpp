// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <optional>
#include <vector>

#include "panoptes/camera/fault_injection.h"
#include "panoptes/time.h"

namespace panoptes::camera {
namespace {

std::vector<std::optional<TimeNs>> fates(FaultInjector injector, int count) {
  std::vector<std::optional<TimeNs>> result;
  for (int i = 0; i < count; ++i) result.push_back(injector.next_delay());
  return result;
}

TEST(FaultInjector, InactiveByDefaultAndPassesEverythingAtOnce) {
  FaultInjector injector;
  EXPECT_FALSE(injector.active());
  for (int i = 0; i < 100; ++i) EXPECT_EQ(injector.next_delay(), TimeNs{0});
  EXPECT_EQ(injector.injected_losses(), 0u);
}

TEST(FaultInjector, SameSeedSameFatesOtherSeedOtherFates) {
  const auto first = fates(FaultInjector(0.3, 5.0, 42), 200);
  EXPECT_EQ(first, fates(FaultInjector(0.3, 5.0, 42), 200));
  EXPECT_NE(first, fates(FaultInjector(0.3, 5.0, 43), 200));
}

TEST(FaultInjector, LossFractionAndJitterRangeAsAsked) {
  FaultInjector injector(0.25, 2.0, 7);
  EXPECT_TRUE(injector.active());
  EXPECT_TRUE(injector.jitters());
  const int count = 20000;
  int lost = 0;
  TimeNs longest = 0;
  for (int i = 0; i < count; ++i) {
    const auto delay = injector.next_delay();
    if (!delay) {
      ++lost;
      continue;
    }
    EXPECT_GE(*delay, 0);
    EXPECT_LE(*delay, 4 * kNsPerMillisecond);  // uniform in [0, 2 · jitter]
    longest = std::max(longest, *delay);
  }
  EXPECT_EQ(injector.injected_losses(), static_cast<std::uint64_t>(lost));
  // 20000 draws at p = 0.25: sigma ≈ 61, so ±400 is far outside chance.
  EXPECT_NEAR(lost, count / 4.0, 400);
  EXPECT_GT(longest, 3 * kNsPerMillisecond);
}

TEST(FaultInjector, LossOnlySendsTheRestAtOnce) {
  FaultInjector injector(0.5, 0.0, 1);
  EXPECT_FALSE(injector.jitters());
  for (int i = 0; i < 100; ++i) {
    const auto delay = injector.next_delay();
    if (delay) {
      EXPECT_EQ(*delay, 0);
    }
  }
  EXPECT_GT(injector.injected_losses(), 20u);
}

TEST(DelayLine, SendsWhatIsDueInDueOrder) {
  DelayLine<int> line;
  line.push(30, 3);
  line.push(10, 1);
  line.push(20, 2);
  std::vector<int> written;
  const auto write = [&written](const int& value) { written.push_back(value); };
  line.send_due(5, write);
  EXPECT_TRUE(written.empty());
  line.send_due(20, write);
  EXPECT_EQ(written, (std::vector<int>{1, 2}));
  EXPECT_EQ(line.size(), 1u);
  line.send_due(100, write);
  EXPECT_EQ(written, (std::vector<int>{1, 2, 3}));
}

}  // namespace
}  // namespace panoptes::camera
