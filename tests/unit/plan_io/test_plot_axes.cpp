// SPDX-License-Identifier: Apache-2.0
// The report's axis ticks (docs/planner.md, "Reading the report"): values 1, 2 or 5 times a power
// of ten apart, labels with the decimals the step needs, 1-2-5 per decade on a long log axis, and
// the plot frame's value-to-pixel mapping.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "panoptes/plan_io/plot_axes.h"

namespace panoptes::planner {
namespace {

std::vector<std::string> labels(const std::vector<Tick>& ticks) {
  std::vector<std::string> out;
  for (const Tick& tick : ticks) out.push_back(tick.label);
  return out;
}

TEST(PlotAxes, LinearTicksAreNiceStepsWithTheirDecimals) {
  EXPECT_EQ(labels(linear_ticks(-3.3, 3.3, 10)),
            (std::vector<std::string>{"-3", "-2", "-1", "0", "1", "2", "3"}));
  EXPECT_EQ(labels(linear_ticks(1, 41, 10)),
            (std::vector<std::string>{"5", "10", "15", "20", "25", "30", "35", "40"}));
  EXPECT_EQ(labels(linear_ticks(3.98, 5.3, 8)),
            (std::vector<std::string>{"4.0", "4.2", "4.4", "4.6", "4.8", "5.0", "5.2"}));
  EXPECT_EQ(labels(linear_ticks(-0.26, 0.1, 4)), (std::vector<std::string>{"-0.2", "-0.1", "0.0", "0.1"}));
  EXPECT_TRUE(linear_ticks(1, 1, 5).empty());
}

TEST(PlotAxes, LogTicksAreOneTwoFivePerDecade) {
  EXPECT_EQ(labels(log_ticks(0.0015, 0.6)),
            (std::vector<std::string>{"0.002", "0.005", "0.01", "0.02", "0.05", "0.1", "0.2", "0.5"}));
  EXPECT_EQ(labels(log_ticks(0.00001, 1.5)),
            (std::vector<std::string>{"0.00001", "0.0001", "0.001", "0.01", "0.1", "1"}));
  // Less than a decade: linear steps.
  EXPECT_EQ(labels(log_ticks(3.98, 5.3)),
            (std::vector<std::string>{"4.0", "4.2", "4.4", "4.6", "4.8", "5.0", "5.2"}));
  EXPECT_TRUE(log_ticks(0, 1).empty());
}

TEST(PlotAxes, FrameMapsValuesToPixels) {
  PlotFrame frame;
  frame.area = cv::Rect(100, 50, 401, 201);
  frame.x_lo = 0;
  frame.x_hi = 4;
  frame.y_lo = -2;  // log10: 0.01 to 1
  frame.y_hi = 0;
  frame.log_y = true;
  EXPECT_EQ(frame.column(0), 100);
  EXPECT_EQ(frame.column(1), 200);
  EXPECT_EQ(frame.column(4), 500);
  EXPECT_EQ(frame.row(1.0), 50);
  EXPECT_EQ(frame.row(0.1), 150);
  EXPECT_EQ(frame.row(0.01), 250);
}

}  // namespace
}  // namespace panoptes::planner
