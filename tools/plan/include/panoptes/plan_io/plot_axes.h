// SPDX-License-Identifier: Apache-2.0
// Axes for the planner's report figures (docs/planner.md, "Reading the report"): tick values at 1, 2
// or 5 times a power of ten with their labels, and a plot frame with tick marks, numbers and axis
// titles drawn with OpenCV's Hershey font.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace panoptes::planner {

struct Tick {
  double value = 0;
  std::string label;  // as few decimals as the step between ticks needs
};

// Ticks over [lo, hi], 1, 2 or 5 times a power of ten apart, at most about `count` of them.
std::vector<Tick> linear_ticks(double lo, double hi, int count);

// Ticks for a logarithmic axis over [lo, hi] (both > 0): 1, 2 and 5 of each decade when the range
// spans a decade or more (whole decades only beyond four), else linear_ticks (a short log axis is
// nearly linear).
std::vector<Tick> log_ticks(double lo, double hi);

// A rectangle of the image and the values it spans: x from left to right, y from bottom to top
// (log10 of the values when `log_y`).
struct PlotFrame {
  cv::Rect area;
  double x_lo = 0, x_hi = 1, y_lo = 0, y_hi = 1;
  bool log_y = false;

  int column(double x) const;
  int row(double y) const;  // y in the axis's units (the value itself, also when log_y)
};

struct AxisTitles {
  std::string x, y;
};

// The frame's left and bottom axes in black, with outward tick marks, numbers and titles (the y
// title turned to read upwards).
void draw_axes(cv::Mat& image, const PlotFrame& frame, const std::vector<Tick>& x_ticks,
               const std::vector<Tick>& y_ticks, const AxisTitles& titles);

// Text in the report's font, black, with its baseline's left end at `origin`.
void draw_label(cv::Mat& image, const std::string& text, cv::Point origin, double scale = 0.45);

}  // namespace panoptes::planner
