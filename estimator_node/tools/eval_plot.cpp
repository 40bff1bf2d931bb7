// SPDX-License-Identifier: Apache-2.0
#include "eval_plot.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <stdexcept>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

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

}  // namespace

void write_error_plot(const Evaluation& evaluation, const PlotOptions& options,
                      const std::filesystem::path& png) {
  const EvaluationSeries& series = evaluation.series;
  if (series.error_m.size() != evaluation.markers.size() ||
      (evaluation.instants > 0 && series.scene_time_ns.size() != evaluation.instants)) {
    throw std::runtime_error("plot: the evaluation kept no per-instant series");
  }
  const std::vector<std::size_t> plotted = worst_markers(evaluation, options.worst_markers);

  // Layout: title, main panel (error), a strip per plotted marker plus one for all markers
  // (trackable-but-untracked), the shared time axis, the legend on the right.
  const int width = std::max(options.width, 640);
  const int height = std::max(options.height, 400);
  const int strip_height = 14;
  const int strips = static_cast<int>(plotted.size()) + 1;
  const int left = 92;
  const int right = width - 330;
  const int top = 76;
  const int strip_top = height - 48 - strips * strip_height;
  const int bottom = strip_top - 12;
  const int plot_width = right - left;
  cv::Mat image(height, width, CV_8UC3, kWhite);

  const std::size_t count = series.scene_time_ns.size();
  const double t0 = count > 0 ? ns_to_seconds(series.scene_time_ns.front()) : 0.0;
  const double t1 = count > 0 ? ns_to_seconds(series.scene_time_ns.back()) : 1.0;
  const double span = std::max(t1 - t0, 1e-3);
  const auto column_of = [&](double t) {
    return std::clamp(static_cast<int>(std::floor((t - t0) / span * (plot_width - 1))), 0, plot_width - 1);
  };
  const auto x_of = [&](double t) { return left + column_of(t); };

  // Per pixel column: each plotted marker's largest error, the RMS over all markers, and whether
  // markers were trackable but untracked.
  const auto columns = static_cast<std::size_t>(plot_width);
  std::vector<std::vector<CurvePoint>> marker_curves(plotted.size());
  std::vector<bool> marker_broken(plotted.size(), false);
  std::vector<std::vector<std::uint8_t>> marker_state(plotted.size(), std::vector<std::uint8_t>(columns, 0));
  std::vector<double> sum2(columns, 0.0);
  std::vector<std::size_t> samples(columns, 0);
  std::vector<std::size_t> trackable(columns, 0), missed(columns, 0);
  for (std::size_t i = 0; i < count; ++i) {
    const auto c = static_cast<std::size_t>(column_of(ns_to_seconds(series.scene_time_ns[i])));
    for (std::size_t m = 0; m < series.error_m.size(); ++m) {
      const float error = series.error_m[m][i];
      if (!std::isnan(error)) {
        sum2[c] += static_cast<double>(error) * error;
        ++samples[c];
      }
      const std::uint8_t flags = series.flags[m][i];
      if ((flags & EvaluationSeries::kTrackable) != 0) {
        ++trackable[c];
        if ((flags & EvaluationSeries::kTracked) == 0) ++missed[c];
      }
    }
    for (std::size_t p = 0; p < plotted.size(); ++p) {
      const float error = series.error_m[plotted[p]][i];
      const std::uint8_t flags = series.flags[plotted[p]][i];
      if (!std::isnan(error)) {
        bool broken = marker_broken[p];
        add_sample(marker_curves[p], c, error, broken);
        marker_broken[p] = broken;
      } else if ((flags & EvaluationSeries::kHasTruth) != 0) {
        marker_broken[p] = true;  // untracked: the line breaks here
      }
      // Bit 1: trackable somewhere in the column; bit 2: trackable and untracked somewhere; bit 4:
      // the column holds an instant with ground truth.
      if ((flags & EvaluationSeries::kHasTruth) != 0) marker_state[p][c] |= 4;
      if ((flags & EvaluationSeries::kTrackable) != 0) marker_state[p][c] |= 1;
      if ((flags & EvaluationSeries::kTrackable) != 0 && (flags & EvaluationSeries::kTracked) == 0)
        marker_state[p][c] |= 2;
    }
  }
  std::vector<CurvePoint> rms;
  double y_max_mm = 0.5;
  for (std::size_t c = 0; c < columns; ++c) {
    if (samples[c] == 0) continue;
    rms.push_back({c, std::sqrt(sum2[c] / static_cast<double>(samples[c])), rms.empty()});
    y_max_mm = std::max(y_max_mm, rms.back().value * 1e3);
  }
  for (const auto& curve : marker_curves) {
    for (const CurvePoint& point : curve) y_max_mm = std::max(y_max_mm, point.value * 1e3);
  }
  const double y_step = nice_step(y_max_mm, 6);
  y_max_mm = std::ceil(y_max_mm / y_step) * y_step;
  const auto y_of = [&](double error_m) {
    return bottom -
           static_cast<int>(std::lround(std::min(error_m * 1e3, y_max_mm) / y_max_mm * (bottom - top)));
  };

  // Shading behind the curves: columns where a plotted marker was trackable but untracked.
  for (std::size_t c = 0; c < columns; ++c) {
    const bool any = std::any_of(marker_state.begin(), marker_state.end(),
                                 [&](const std::vector<std::uint8_t>& state) { return (state[c] & 2) != 0; });
    if (any)
      cv::line(image, {left + static_cast<int>(c), top}, {left + static_cast<int>(c), bottom},
               kUntrackedShade, 1);
  }

  // Grid and axes.
  for (double y = 0.0; y <= y_max_mm + 1e-9; y += y_step) {
    const int row = y_of(y * 1e-3);
    cv::line(image, {left, row}, {right, row}, kGrid, 1);
    const std::string label = format(y_step < 1.0 ? "%.1f" : "%.0f", y);
    text(image, label, {left - 8 - text_width(label), row + 5}, kBlack);
  }
  const double t_step = nice_step(span, 10);
  for (double t = std::ceil(t0 / t_step) * t_step; t <= t1 + 1e-9; t += t_step) {
    const int x = x_of(t);
    cv::line(image, {x, top}, {x, bottom}, kGrid, 1);
    cv::line(image, {x, strip_top + strips * strip_height}, {x, strip_top + strips * strip_height + 5}, kAxis,
             1);
    const std::string label = format(t_step < 1.0 ? "%.1f" : "%.0f", t);
    text(image, label, {x - text_width(label) / 2, strip_top + strips * strip_height + 20}, kBlack);
  }
  cv::rectangle(image, {left, top}, {right, bottom}, kAxis, 1);
  text(image, "error (mm)", {left - 80, top - 8}, kBlack);
  const std::string x_label = "scene time (s)";
  text(image, x_label, {left + plot_width / 2 - text_width(x_label) / 2, height - 8}, kBlack);

  // Curves: plotted markers (largest error per pixel column), then the overall RMS on top.
  const auto draw_curve = [&](const std::vector<CurvePoint>& curve, const cv::Scalar& colour, int thickness) {
    const auto point = [&](const CurvePoint& p) {
      return cv::Point(left + static_cast<int>(p.column), y_of(p.value));
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
  for (std::size_t p = plotted.size(); p-- > 0;)
    draw_curve(marker_curves[p], kPalette[p % kPalette.size()], 1);
  draw_curve(rms, kBlack, 2);

  // ID switches: dashed verticals, in the marker's colour when it is plotted.
  std::size_t switch_label = 0;
  for (std::size_t m = 0; m < evaluation.markers.size(); ++m) {
    const auto slot = std::find(plotted.begin(), plotted.end(), m);
    const cv::Scalar colour =
        slot == plotted.end() ? kSwitchGrey
                              : kPalette[static_cast<std::size_t>(slot - plotted.begin()) % kPalette.size()];
    for (const IdSwitch& s : evaluation.markers[m].id_switches) {
      const int x = x_of(s.t_s);
      dashed_vertical(image, x, top, bottom, colour);
      if (evaluation.id_switch_count <= 16) {
        const std::string label = std::to_string(s.from_id) + ">" + std::to_string(s.to_id);
        text(image, label, {x + 3, top + 14 + 14 * static_cast<int>(switch_label++ % 4)}, colour, 0.38);
      }
    }
  }

  // Strips: per plotted marker, red where trackable but untracked and grey where not trackable;
  // for all markers, red in proportion to the untracked share of trackable markers.
  for (int s = 0; s < strips; ++s) {
    const int y0 = strip_top + s * strip_height;
    const bool all = s == strips - 1;
    for (std::size_t c = 0; c < columns; ++c) {
      cv::Scalar colour = kWhite;
      if (all) {
        if (trackable[c] > 0 && missed[c] > 0) {
          const double share = static_cast<double>(missed[c]) / static_cast<double>(trackable[c]);
          const double fade = 1.0 - std::min(1.0, 0.15 + 3.0 * share);  // 28% untracked is full red
          colour = cv::Scalar(255 * fade, 255 * fade, 255);
        }
      } else {
        const std::uint8_t state = marker_state[static_cast<std::size_t>(s)][c];
        if ((state & 2) != 0) {
          colour = cv::Scalar(60, 60, 230);
        } else if ((state & 4) != 0 && (state & 1) == 0) {
          colour = kNotTrackable;
        }
      }
      if (colour != kWhite) {
        cv::line(image, {left + static_cast<int>(c), y0 + 1},
                 {left + static_cast<int>(c), y0 + strip_height - 2}, colour, 1);
      }
    }
    cv::rectangle(image, {left, y0}, {right, y0 + strip_height - 1}, kGrid, 1);
    const std::string label = all ? "all" : evaluation.markers[plotted[static_cast<std::size_t>(s)]].name;
    const cv::Scalar label_colour = all ? kBlack : kPalette[static_cast<std::size_t>(s) % kPalette.size()];
    std::string shown = label;
    while (shown.size() > 3 && text_width(shown, 0.35) > left - 6) shown.erase(0, 1);
    text(image, shown, {left - 4 - text_width(shown, 0.35), y0 + strip_height - 3}, label_colour, 0.35);
  }

  // Title and subtitle.
  const std::string title = options.title.empty() ? "Position error over time" : options.title;
  text(image, title, {left - 80, 26}, kBlack, 0.7, 2);
  char subtitle[256];
  std::snprintf(
      subtitle, sizeof subtitle,
      "RMSE %.3f mm, max %.2f mm, coverage %.2f%% (min %.1f%%), ID switches %zu, false records %.2f%%",
      evaluation.rmse_m * 1e3, evaluation.max_error_m * 1e3, 100.0 * evaluation.coverage(),
      100.0 * evaluation.min_coverage, evaluation.id_switch_count,
      100.0 * evaluation.false_record_fraction());
  text(image, subtitle, {left - 80, 50}, kAxis);

  // Legend.
  int y = top + 10;
  const int legend_x = right + 18;
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

  bool written = false;
  try {
    written = cv::imwrite(png.string(), image);
  } catch (const cv::Exception& error) {
    throw std::runtime_error(png.string() + ": cannot write the plot: " + error.what());
  }
  if (!written) throw std::runtime_error(png.string() + ": cannot write the plot");
}

}  // namespace panoptes::estimator
