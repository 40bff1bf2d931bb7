// SPDX-License-Identifier: Apache-2.0
#include "panoptes/plan_io/plot_axes.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

namespace panoptes::planner {

namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kTickScale = 0.45, kTitleScale = 0.5;
constexpr int kTickLength = 5, kGap = 4;
const cv::Scalar kInk(0, 0, 0);

// The number with `decimals` digits after the point; never "-0".
std::string number(double value, int decimals) {
  char text[32];
  std::snprintf(text, sizeof text, "%.*f", std::max(decimals, 0), value == 0.0 ? 0.0 : value);
  return text;
}

// Digits after the point that a value which is a multiple of `step` needs.
int decimals_for(double step) {
  return std::max(0, -static_cast<int>(std::floor(std::log10(step) + 1e-9)));
}

cv::Size text_size(const std::string& text, double scale, int* baseline = nullptr) {
  int below = 0;
  const cv::Size size = cv::getTextSize(text, kFont, scale, 1, &below);
  if (baseline != nullptr) *baseline = below;
  return size;
}

// `text` read from bottom to top (the letters' tops to the left), its box ending at column `right`,
// centred on row `centre`; drawn by darkening only, so nothing under it is erased.
void draw_upwards(cv::Mat& image, const std::string& text, int right, int centre) {
  int baseline = 0;
  const cv::Size size = text_size(text, kTitleScale, &baseline);
  cv::Mat flat(size.height + baseline + 2, size.width + 2, image.type(), cv::Scalar::all(255));
  cv::putText(flat, text, {1, size.height + 1}, kFont, kTitleScale, kInk, 1, cv::LINE_AA);
  cv::Mat turned;
  cv::rotate(flat, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
  cv::Rect where(right - turned.cols, centre - turned.rows / 2, turned.cols, turned.rows);
  where &= cv::Rect(0, 0, image.cols, image.rows);
  if (where.empty()) return;
  cv::Mat target = image(where);
  cv::min(target, turned(cv::Rect(0, 0, where.width, where.height)), target);
}

}  // namespace

std::vector<Tick> linear_ticks(double lo, double hi, int count) {
  std::vector<Tick> ticks;
  if (!(hi > lo) || count < 1) return ticks;
  // The smallest of 1, 2, 5 × 10^k that gives at most about `count` steps.
  const double rough = (hi - lo) / count;
  const double decade = std::pow(10.0, std::floor(std::log10(rough)));
  double step = 10.0 * decade;
  for (const double mantissa : {1.0, 2.0, 5.0}) {
    if (mantissa * decade >= rough * (1 - 1e-9)) {
      step = mantissa * decade;
      break;
    }
  }
  const int decimals = decimals_for(step);
  for (double n = std::ceil(lo / step - 1e-9); n * step <= hi + 1e-9 * step; n += 1.0)
    ticks.push_back({n * step, number(n * step, decimals)});
  return ticks;
}

std::vector<Tick> log_ticks(double lo, double hi) {
  if (!(lo > 0) || !(hi > lo)) return {};
  if (hi / lo < 10.0) return linear_ticks(lo, hi, 8);
  const bool decades_only = hi / lo > 1e4;
  std::vector<Tick> ticks;
  for (int exponent = static_cast<int>(std::floor(std::log10(lo)));
       exponent <= static_cast<int>(std::ceil(std::log10(hi))); ++exponent) {
    const double decade = std::pow(10.0, exponent);
    for (const double mantissa : {1.0, 2.0, 5.0}) {
      const double value = mantissa * decade;
      if ((decades_only && mantissa != 1.0) || value < lo * (1 - 1e-9) || value > hi * (1 + 1e-9)) continue;
      ticks.push_back({value, number(value, decimals_for(value))});
    }
  }
  return ticks;
}

int PlotFrame::column(double x) const {
  return area.x + static_cast<int>(std::lround((x - x_lo) / (x_hi - x_lo) * (area.width - 1)));
}

int PlotFrame::row(double y) const {
  const double at = log_y ? std::log10(std::max(y, 1e-300)) : y;
  return area.y + area.height - 1 -
         static_cast<int>(std::lround((at - y_lo) / (y_hi - y_lo) * (area.height - 1)));
}

void draw_label(cv::Mat& image, const std::string& text, cv::Point origin, double scale) {
  cv::putText(image, text, origin, kFont, scale, kInk, 1, cv::LINE_AA);
}

void draw_axes(cv::Mat& image, const PlotFrame& frame, const std::vector<Tick>& x_ticks,
               const std::vector<Tick>& y_ticks, const AxisTitles& titles) {
  const int left = frame.area.x, bottom = frame.area.y + frame.area.height - 1;
  const int right = frame.area.x + frame.area.width - 1;
  cv::line(image, {left, bottom}, {right, bottom}, kInk, 1);
  cv::line(image, {left, frame.area.y}, {left, bottom}, kInk, 1);
  int label_height = 0;
  for (const Tick& tick : x_ticks) {
    const int x = frame.column(tick.value);
    if (x < left || x > right) continue;
    cv::line(image, {x, bottom + 1}, {x, bottom + kTickLength}, kInk, 1);
    const cv::Size size = text_size(tick.label, kTickScale);
    label_height = std::max(label_height, size.height);
    draw_label(image, tick.label, {x - size.width / 2, bottom + kTickLength + kGap + size.height},
               kTickScale);
  }
  int label_width = 0;
  for (const Tick& tick : y_ticks) {
    const int y = frame.row(tick.value);
    if (y < frame.area.y || y > bottom) continue;
    cv::line(image, {left - kTickLength, y}, {left - 1, y}, kInk, 1);
    const cv::Size size = text_size(tick.label, kTickScale);
    label_width = std::max(label_width, size.width);
    draw_label(image, tick.label, {left - kTickLength - kGap - size.width, y + size.height / 2}, kTickScale);
  }
  const cv::Size x_title = text_size(titles.x, kTitleScale);
  draw_label(image, titles.x,
             {left + (frame.area.width - x_title.width) / 2,
              bottom + kTickLength + 2 * kGap + label_height + kGap + x_title.height},
             kTitleScale);
  draw_upwards(image, titles.y, left - kTickLength - 2 * kGap - label_width - kGap,
               frame.area.y + frame.area.height / 2);
}

}  // namespace panoptes::planner
