// SPDX-License-Identifier: Apache-2.0
#include "panoptes/eval_plot/eval_plot.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <stdexcept>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "panoptes/image_file_cv.h"

namespace panoptes::estimator {

namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kTextScale = 0.45;
const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kWhite(255, 255, 255);
const cv::Scalar kGrid(225, 225, 225);
const cv::Scalar kAxis(90, 90, 90);
const cv::Scalar kUntrackedShade(215, 215, 255);  // light red: trackable but untracked
const cv::Scalar kNotTrackable(235, 235, 235);    // light grey: fewer than two cameras saw it
const cv::Scalar kSwitchGrey(110, 110, 110);

// A qualitative palette (BGR) that stays distinguishable on white.
const std::array<cv::Scalar, 10> kPalette = {
    cv::Scalar(180, 119, 31),  cv::Scalar(14, 127, 255), cv::Scalar(44, 160, 44),   cv::Scalar(40, 39, 214),
    cv::Scalar(189, 103, 148), cv::Scalar(75, 86, 140),  cv::Scalar(194, 119, 227), cv::Scalar(34, 189, 188),
    cv::Scalar(207, 190, 23),  cv::Scalar(127, 127, 127)};

// 1, 2 or 5 times a power of ten, so that `span` holds about `ticks` steps.
double nice_step(double span, int ticks) {
  const double raw = span / std::max(ticks, 1);
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double factor : {1.0, 2.0, 5.0}) {
    if (factor * power >= raw) return factor * power;
  }
  return 10.0 * power;
}

void text(cv::Mat& image, const std::string& label, cv::Point at, const cv::Scalar& colour,
          double scale = kTextScale, int thickness = 1) {
  cv::putText(image, label, at, kFont, scale, colour, thickness, cv::LINE_AA);
}

int text_width(const std::string& label, double scale = kTextScale) {
  int baseline = 0;
  return cv::getTextSize(label, kFont, scale, 1, &baseline).width;
}

void dashed_vertical(cv::Mat& image, int x, int top, int bottom, const cv::Scalar& colour) {
  for (int y = top; y < bottom; y += 7) cv::line(image, {x, y}, {x, std::min(y + 4, bottom)}, colour, 1);
}

// A curve over pixel columns; a point with `starts_segment` is not joined to the one before.
struct CurvePoint {
  std::size_t column = 0;
  double value = 0.0;
  bool starts_segment = true;
};

// Adds a sample at `column`: keeps the largest value per column, and starts a new segment after a
// break (an instant at which the quantity was undefined).
void add_sample(std::vector<CurvePoint>& curve, std::size_t column, double value, bool& broken) {
  if (!curve.empty() && curve.back().column == column && !broken) {
    curve.back().value = std::max(curve.back().value, value);
    return;
  }
  curve.push_back({column, value, broken || curve.empty()});
  broken = false;
}

std::string format(const char* pattern, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, pattern, value);
  return buffer;
}

// Markers drawn individually: half of them the highest RMSE, the rest the lowest coverage.
std::vector<std::size_t> worst_markers(const Evaluation& evaluation, std::size_t count) {
  const auto& markers = evaluation.markers;
  count = std::min(count, markers.size());
  std::vector<std::size_t> by_rmse(markers.size());
  std::iota(by_rmse.begin(), by_rmse.end(), 0);
  std::vector<std::size_t> by_coverage = by_rmse;
  std::stable_sort(by_rmse.begin(), by_rmse.end(),
                   [&](std::size_t a, std::size_t b) { return markers[a].rmse_m > markers[b].rmse_m; });
  std::stable_sort(by_coverage.begin(), by_coverage.end(), [&](std::size_t a, std::size_t b) {
    return markers[a].coverage() < markers[b].coverage();
  });
  std::vector<std::size_t> chosen;
  const auto take = [&](std::size_t m) {
    if (chosen.size() < count && std::find(chosen.begin(), chosen.end(), m) == chosen.end())
      chosen.push_back(m);
  };
  for (std::size_t i = 0; i < by_rmse.size() && chosen.size() < (count + 1) / 2; ++i) take(by_rmse[i]);
  for (std::size_t m : by_coverage) take(m);
  return chosen;
}

// Where everything goes on the image, and how scene time and error map to pixels. Layout: title,
// main panel (error), a strip per plotted marker plus one for all markers (trackable-but-untracked),
// the shared time axis, the legend on the right.
struct PlotFrame {
  int width = 0, height = 0;
  int strip_height = 14, strips = 0;
  int left = 92, right = 0, top = 76, strip_top = 0, bottom = 0, plot_width = 0;
  double t0 = 0.0, t1 = 1.0, span = 1.0;  // scene time, s
  double y_max_mm = 0.5, y_step = 1.0;    // error axis

  PlotFrame(const EvaluationSeries& series, const PlotOptions& options, std::size_t plotted)
      : width(std::max(options.width, 640)), height(std::max(options.height, 400)) {
    strips = static_cast<int>(plotted) + 1;
    right = width - 330;
    strip_top = height - 48 - strips * strip_height;
    bottom = strip_top - 12;
    plot_width = right - left;
    const std::size_t count = series.scene_time_ns.size();
    t0 = count > 0 ? ns_to_seconds(series.scene_time_ns.front()) : 0.0;
    t1 = count > 0 ? ns_to_seconds(series.scene_time_ns.back()) : 1.0;
    span = std::max(t1 - t0, 1e-3);
  }
  std::size_t columns() const { return static_cast<std::size_t>(plot_width); }
  int column_of(double t) const {
    return std::clamp(static_cast<int>(std::floor((t - t0) / span * (plot_width - 1))), 0, plot_width - 1);
  }
  int x_of(double t) const { return left + column_of(t); }
  int y_of(double error_m) const {
    return bottom -
           static_cast<int>(std::lround(std::min(error_m * 1e3, y_max_mm) / y_max_mm * (bottom - top)));
  }
};

// Per pixel column: each plotted marker's largest error and state, the RMS over all markers, and
// how many markers were trackable and how many of those untracked.
struct PlotColumns {
  std::vector<std::vector<CurvePoint>> marker_curves;
  // Bit 1: trackable somewhere in the column; bit 2: trackable and untracked somewhere; bit 4: the
  // column holds an instant with ground truth.
  std::vector<std::vector<std::uint8_t>> marker_state;
  std::vector<CurvePoint> rms;
  std::vector<std::size_t> trackable, missed;
};

PlotColumns bin_columns(const EvaluationSeries& series, const std::vector<std::size_t>& plotted,
                        const PlotFrame& frame) {
  const std::size_t columns = frame.columns();
  PlotColumns out;
  out.marker_curves.resize(plotted.size());
  out.marker_state.assign(plotted.size(), std::vector<std::uint8_t>(columns, 0));
  out.trackable.assign(columns, 0);
  out.missed.assign(columns, 0);
  std::vector<bool> marker_broken(plotted.size(), false);
  std::vector<double> sum2(columns, 0.0);
  std::vector<std::size_t> samples(columns, 0);
  for (std::size_t i = 0; i < series.scene_time_ns.size(); ++i) {
    const auto c = static_cast<std::size_t>(frame.column_of(ns_to_seconds(series.scene_time_ns[i])));
    for (std::size_t m = 0; m < series.error_m.size(); ++m) {
      const float error = series.error_m[m][i];
      if (!std::isnan(error)) {
        sum2[c] += static_cast<double>(error) * error;
        ++samples[c];
      }
      const std::uint8_t flags = series.flags[m][i];
      if ((flags & EvaluationSeries::kTrackable) != 0) {
        ++out.trackable[c];
        if ((flags & EvaluationSeries::kTracked) == 0) ++out.missed[c];
      }
    }
    for (std::size_t p = 0; p < plotted.size(); ++p) {
      const float error = series.error_m[plotted[p]][i];
      const std::uint8_t flags = series.flags[plotted[p]][i];
      if (!std::isnan(error)) {
        bool broken = marker_broken[p];
        add_sample(out.marker_curves[p], c, error, broken);
        marker_broken[p] = broken;
      } else if ((flags & EvaluationSeries::kHasTruth) != 0) {
        marker_broken[p] = true;  // untracked: the line breaks here
      }
      if ((flags & EvaluationSeries::kHasTruth) != 0) out.marker_state[p][c] |= 4;
      if ((flags & EvaluationSeries::kTrackable) != 0) out.marker_state[p][c] |= 1;
      if ((flags & EvaluationSeries::kTrackable) != 0 && (flags & EvaluationSeries::kTracked) == 0)
        out.marker_state[p][c] |= 2;
    }
  }
  for (std::size_t c = 0; c < columns; ++c) {
    if (samples[c] == 0) continue;
    out.rms.push_back({c, std::sqrt(sum2[c] / static_cast<double>(samples[c])), out.rms.empty()});
  }
  return out;
}

// The error axis: up to the largest value drawn, in nice steps.
void scale_error_axis(PlotFrame& frame, const PlotColumns& columns) {
  double y_max_mm = 0.5;
  for (const CurvePoint& point : columns.rms) y_max_mm = std::max(y_max_mm, point.value * 1e3);
  for (const auto& curve : columns.marker_curves) {
    for (const CurvePoint& point : curve) y_max_mm = std::max(y_max_mm, point.value * 1e3);
  }
  frame.y_step = nice_step(y_max_mm, 6);
  frame.y_max_mm = std::ceil(y_max_mm / frame.y_step) * frame.y_step;
}

// Shading where a plotted marker was trackable but untracked, then the grid, axes and their labels.
void draw_axes(cv::Mat& image, const PlotFrame& f, const PlotColumns& columns) {
  for (std::size_t c = 0; c < f.columns(); ++c) {
    const bool any = std::any_of(columns.marker_state.begin(), columns.marker_state.end(),
                                 [&](const std::vector<std::uint8_t>& state) { return (state[c] & 2) != 0; });
    if (any)
      cv::line(image, {f.left + static_cast<int>(c), f.top}, {f.left + static_cast<int>(c), f.bottom},
               kUntrackedShade, 1);
  }
  for (double y = 0.0; y <= f.y_max_mm + 1e-9; y += f.y_step) {
    const int row = f.y_of(y * 1e-3);
    cv::line(image, {f.left, row}, {f.right, row}, kGrid, 1);
    const std::string label = format(f.y_step < 1.0 ? "%.1f" : "%.0f", y);
    text(image, label, {f.left - 8 - text_width(label), row + 5}, kBlack);
  }
  const double t_step = nice_step(f.span, 10);
  const int axis_y = f.strip_top + f.strips * f.strip_height;
  for (double t = std::ceil(f.t0 / t_step) * t_step; t <= f.t1 + 1e-9; t += t_step) {
    const int x = f.x_of(t);
    cv::line(image, {x, f.top}, {x, f.bottom}, kGrid, 1);
    cv::line(image, {x, axis_y}, {x, axis_y + 5}, kAxis, 1);
    const std::string label = format(t_step < 1.0 ? "%.1f" : "%.0f", t);
    text(image, label, {x - text_width(label) / 2, axis_y + 20}, kBlack);
  }
  cv::rectangle(image, {f.left, f.top}, {f.right, f.bottom}, kAxis, 1);
  text(image, "error (mm)", {f.left - 80, f.top - 8}, kBlack);
  const std::string x_label = "scene time (s)";
  text(image, x_label, {f.left + f.plot_width / 2 - text_width(x_label) / 2, f.height - 8}, kBlack);
}

// Curves: plotted markers (largest error per pixel column), then the overall RMS on top.
void draw_curves(cv::Mat& image, const PlotFrame& f, const PlotColumns& columns) {
  const auto draw_curve = [&](const std::vector<CurvePoint>& curve, const cv::Scalar& colour, int thickness) {
    const auto point = [&](const CurvePoint& p) {
      return cv::Point(f.left + static_cast<int>(p.column), f.y_of(p.value));
    };
    for (std::size_t i = 0; i < curve.size(); ++i) {
      const bool joined_before = !curve[i].starts_segment;
      const bool joined_after = i + 1 < curve.size() && !curve[i + 1].starts_segment;
      if (joined_before) {
        cv::line(image, point(curve[i - 1]), point(curve[i]), colour, thickness, cv::LINE_AA);
      } else if (!joined_after) {
        cv::circle(image, point(curve[i]), thickness, colour, cv::FILLED, cv::LINE_AA);  // an isolated sample
      }
    }
  };
  for (std::size_t p = columns.marker_curves.size(); p-- > 0;)
    draw_curve(columns.marker_curves[p], kPalette[p % kPalette.size()], 1);
  draw_curve(columns.rms, kBlack, 2);
}

// ID switches: dashed verticals, in the marker's colour when it is plotted.
void draw_id_switches(cv::Mat& image, const PlotFrame& f, const Evaluation& evaluation,
                      const std::vector<std::size_t>& plotted) {
  std::size_t switch_label = 0;
  for (std::size_t m = 0; m < evaluation.markers.size(); ++m) {
    const auto slot = std::find(plotted.begin(), plotted.end(), m);
    const cv::Scalar colour =
        slot == plotted.end() ? kSwitchGrey
                              : kPalette[static_cast<std::size_t>(slot - plotted.begin()) % kPalette.size()];
    for (const IdSwitch& s : evaluation.markers[m].id_switches) {
      const int x = f.x_of(s.t_s);
      dashed_vertical(image, x, f.top, f.bottom, colour);
      if (evaluation.id_switch_count <= 16) {
        const std::string label = std::to_string(s.from_id) + ">" + std::to_string(s.to_id);
        text(image, label, {x + 3, f.top + 14 + 14 * static_cast<int>(switch_label++ % 4)}, colour, 0.38);
      }
    }
  }
}

// Strips: per plotted marker, red where trackable but untracked and grey where not trackable;
// for all markers, red in proportion to the untracked share of trackable markers.
void draw_strips(cv::Mat& image, const PlotFrame& f, const PlotColumns& columns, const Evaluation& evaluation,
                 const std::vector<std::size_t>& plotted) {
  for (int s = 0; s < f.strips; ++s) {
    const int y0 = f.strip_top + s * f.strip_height;
    const bool all = s == f.strips - 1;
    for (std::size_t c = 0; c < f.columns(); ++c) {
      cv::Scalar colour = kWhite;
      if (all) {
        if (columns.trackable[c] > 0 && columns.missed[c] > 0) {
          const double share =
              static_cast<double>(columns.missed[c]) / static_cast<double>(columns.trackable[c]);
          const double fade = 1.0 - std::min(1.0, 0.15 + 3.0 * share);  // 28% untracked is full red
          colour = cv::Scalar(255 * fade, 255 * fade, 255);
        }
      } else {
        const std::uint8_t state = columns.marker_state[static_cast<std::size_t>(s)][c];
        if ((state & 2) != 0) {
          colour = cv::Scalar(60, 60, 230);
        } else if ((state & 4) != 0 && (state & 1) == 0) {
          colour = kNotTrackable;
        }
      }
      if (colour != kWhite) {
        cv::line(image, {f.left + static_cast<int>(c), y0 + 1},
                 {f.left + static_cast<int>(c), y0 + f.strip_height - 2}, colour, 1);
      }
    }
    cv::rectangle(image, {f.left, y0}, {f.right, y0 + f.strip_height - 1}, kGrid, 1);
    const std::string label = all ? "all" : evaluation.markers[plotted[static_cast<std::size_t>(s)]].name;
    const cv::Scalar label_colour = all ? kBlack : kPalette[static_cast<std::size_t>(s) % kPalette.size()];
    std::string shown = label;
    while (shown.size() > 3 && text_width(shown, 0.35) > f.left - 6) shown.erase(0, 1);
    text(image, shown, {f.left - 4 - text_width(shown, 0.35), y0 + f.strip_height - 3}, label_colour, 0.35);
  }
}

void draw_title(cv::Mat& image, const PlotFrame& f, const Evaluation& evaluation,
                const PlotOptions& options) {
  const std::string title = options.title.empty() ? "Position error over time" : options.title;
  text(image, title, {f.left - 80, 26}, kBlack, 0.7, 2);
  char subtitle[256];
  std::snprintf(
      subtitle, sizeof subtitle,
      "RMSE %.3f mm, max %.2f mm, coverage %.2f%% (min %.1f%%), ID switches %zu, false records %.2f%%",
      evaluation.rmse_m * 1e3, evaluation.max_error_m * 1e3, 100.0 * evaluation.coverage(),
      100.0 * evaluation.min_coverage, evaluation.id_switch_count,
      100.0 * evaluation.false_record_fraction());
  text(image, subtitle, {f.left - 80, 50}, kAxis);
}

void draw_legend(cv::Mat& image, const PlotFrame& f, const Evaluation& evaluation,
                 const std::vector<std::size_t>& plotted) {
  int y = f.top + 10;
  const int legend_x = f.right + 18;
  const auto legend_line = [&](const cv::Scalar& colour, int thickness, const std::string& label) {
    cv::line(image, {legend_x, y - 4}, {legend_x + 24, y - 4}, colour, thickness, cv::LINE_AA);
    text(image, label, {legend_x + 32, y}, kBlack);
    y += 20;
  };
  legend_line(kBlack, 2, "RMS over all markers");
  for (std::size_t p = 0; p < plotted.size(); ++p) {
    const MarkerEvaluation& marker = evaluation.markers[plotted[p]];
    char label[128];
    std::snprintf(label, sizeof label, "%s: %.2f mm, %.1f%%", marker.name.c_str(), marker.rmse_m * 1e3,
                  100.0 * marker.coverage());
    legend_line(kPalette[p % kPalette.size()], 1, label);
  }
  text(image, "marker: RMSE, coverage; curves show the", {legend_x, y}, kAxis, 0.38);
  y += 16;
  text(image, "largest error per pixel column", {legend_x, y}, kAxis, 0.38);
  y += 26;
  dashed_vertical(image, legend_x + 12, y - 14, y + 2, kSwitchGrey);
  text(image, "ID switch (from>to)", {legend_x + 32, y}, kBlack);
  y += 22;
  cv::rectangle(image, {legend_x, y - 11}, {legend_x + 24, y + 1}, kUntrackedShade, cv::FILLED);
  text(image, "trackable, untracked", {legend_x + 32, y}, kBlack);
  y += 22;
  cv::rectangle(image, {legend_x, y - 11}, {legend_x + 24, y + 1}, kNotTrackable, cv::FILLED);
  text(image, "not trackable (< " + std::to_string(evaluation.options.trackable_min_cameras) + " cameras)",
       {legend_x + 32, y}, kBlack);
}

}  // namespace

void write_error_plot(const Evaluation& evaluation, const PlotOptions& options,
                      const std::filesystem::path& png) {
  const EvaluationSeries& series = evaluation.series;
  if (series.error_m.size() != evaluation.markers.size() ||
      (evaluation.instants > 0 && series.scene_time_ns.size() != evaluation.instants)) {
    throw std::runtime_error("plot: the evaluation kept no per-instant series");
  }
  const std::vector<std::size_t> plotted = worst_markers(evaluation, options.worst_markers);
  PlotFrame frame(series, options, plotted.size());
  const PlotColumns columns = bin_columns(series, plotted, frame);
  scale_error_axis(frame, columns);

  cv::Mat image(frame.height, frame.width, CV_8UC3, kWhite);
  draw_axes(image, frame, columns);
  draw_curves(image, frame, columns);
  draw_id_switches(image, frame, evaluation, plotted);
  draw_strips(image, frame, columns, evaluation, plotted);
  draw_title(image, frame, evaluation, options);
  draw_legend(image, frame, evaluation, plotted);

  write_png(png, view_of(image));
}

}  // namespace panoptes::estimator
