// SPDX-License-Identifier: Apache-2.0
#include "panoptes/plan_io/plan_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "panoptes/image_file_cv.h"

#include "panoptes/plan_io/plot_axes.h"

namespace panoptes::planner {

namespace {

namespace fs = std::filesystem;

const cv::Scalar kBlack(0, 0, 0), kGrey(150, 150, 150), kObstacle(120, 120, 120), kObstacleEdge(90, 90, 90),
    kVolume(200, 120, 40), kMount(60, 160, 60), kCamera(30, 30, 200), kWhite(255, 255, 255);

// World axes (a, b) of a view (b up on the image), fitted to the content with the same margin on
// every side and the same scale on both axes; the image is as tall as the content needs.
struct View {
  static constexpr int kLeft = 75, kRight = 60, kTop = 40, kBottom = 62;
  static constexpr int kMaxPlotWidth = 820, kMaxPlotHeight = 620, kMinWidth = 640;
  int a = 0, b = 1;
  double scale = 1;  // pixels per metre
  PlotFrame frame;   // the plot area on the image and the metres it spans
  cv::Size image_size;

  View(int axis_a, int axis_b, const Eigen::Vector2d& low, const Eigen::Vector2d& high)
      : a(axis_a), b(axis_b) {
    const Eigen::Vector2d span = (high - low).cwiseMax(0.1);
    const double pad = std::max(0.04 * span.maxCoeff(), 0.1);
    const Eigen::Vector2d lo = low - Eigen::Vector2d::Constant(pad);
    const Eigen::Vector2d extent = span + Eigen::Vector2d::Constant(2 * pad);
    scale = std::min(kMaxPlotWidth / extent.x(), kMaxPlotHeight / extent.y());
    const int width = static_cast<int>(std::lround(extent.x() * scale)) + 1;
    const int height = static_cast<int>(std::lround(extent.y() * scale)) + 1;
    frame.area = cv::Rect(kLeft, kTop, width, height);
    frame.x_lo = lo.x();
    frame.x_hi = lo.x() + (width - 1) / scale;
    frame.y_lo = lo.y();
    frame.y_hi = lo.y() + (height - 1) / scale;
    image_size = cv::Size(std::max(kLeft + width + kRight, kMinWidth), kTop + height + kBottom);
  }
  // A world point's pixel in the plot area's own coordinates (draw on image(frame.area)).
  cv::Point px(const Eigen::Vector3d& p) const {
    return {frame.column(p[a]) - frame.area.x, frame.row(p[b]) - frame.area.y};
  }
};

// What a view shows on axes (a, b): the volume, the mounts, the obstacles and the cameras.
std::pair<Eigen::Vector2d, Eigen::Vector2d> content_bounds(const ReportInput& input, int a, int b) {
  const Room& room = *input.room;
  Eigen::Vector2d lo(room.volume.min[a], room.volume.min[b]), hi(room.volume.max[a], room.volume.max[b]);
  const auto extend = [&](const Eigen::Vector3d& p) {
    lo = lo.cwiseMin(Eigen::Vector2d(p[a], p[b]));
    hi = hi.cwiseMax(Eigen::Vector2d(p[a], p[b]));
  };
  for (const auto& mount : room.mounts)
    for (const double s : {0.0, 1.0})
      for (const double t : {0.0, 1.0}) extend(mount.at(s, t));
  for (const auto& obstacle : room.obstacles) {
    extend(obstacle.min);
    extend(obstacle.max);
  }
  for (const auto& camera : input.cameras) extend(camera.model.center_world());
  return {lo, hi};
}

// Green where at least k cameras see a point under every occluder, red where they do under half
// of the occluders or fewer.
cv::Scalar coverage_colour(double p) {
  p = std::clamp(2.0 * p - 1.0, 0.0, 1.0);
  return {60, 60 + 170 * p, 230 - 170 * p};
}

// Obstacles see-through (what stands behind them along the hidden axis stays visible) with a
// solid outline at their true extent.
void draw_obstacles(cv::Mat& plot, const View& view, const std::vector<Box>& obstacles) {
  if (obstacles.empty()) return;
  cv::Mat shade = plot.clone();
  for (const auto& obstacle : obstacles)
    cv::rectangle(shade, view.px(obstacle.min), view.px(obstacle.max), kObstacle, cv::FILLED);
  cv::addWeighted(shade, 0.45, plot, 0.55, 0.0, plot);
  for (const auto& obstacle : obstacles)
    cv::rectangle(plot, view.px(obstacle.min), view.px(obstacle.max), kObstacleEdge, 2);
}

void draw_frustum(cv::Mat& plot, const View& view, const PlannedCamera& camera, double length) {
  const auto& K = camera.model.intrinsics();
  const Eigen::Vector3d centre = camera.model.center_world();
  const std::array<Eigen::Vector2d, 4> corners = {Eigen::Vector2d(0, 0), Eigen::Vector2d(K.width, 0),
                                                  Eigen::Vector2d(K.width, K.height),
                                                  Eigen::Vector2d(0, K.height)};
  std::array<cv::Point, 4> far{};
  for (std::size_t i = 0; i < corners.size(); ++i) {
    far[i] = view.px(centre + length * camera.model.pixel_to_world_ray(corners[i]));
    cv::line(plot, view.px(centre), far[i], kGrey, 1, cv::LINE_AA);
  }
  for (std::size_t i = 0; i < far.size(); ++i)
    cv::line(plot, far[i], far[(i + 1) % far.size()], kGrey, 1, cv::LINE_AA);
}

// Mounts, coverage, obstacles, the volume and the frusta.
void draw_scene(cv::Mat& plot, const View& view, const ReportInput& input) {
  const Room& room = *input.room;
  for (const auto& mount : room.mounts) {
    std::vector<cv::Point> poly = {view.px(mount.at(0, 0)), view.px(mount.at(1, 0)), view.px(mount.at(1, 1)),
                                   view.px(mount.at(0, 1))};
    cv::polylines(plot, poly, true, kMount, 1, cv::LINE_AA);
  }
  // Points drawn far-to-near along the hidden axis would need sorting; coverage is a mean anyway.
  const auto& points = input.samples->points;
  for (std::size_t i = 0; i < points.size(); ++i)
    cv::circle(plot, view.px(points[i]), 2, coverage_colour(input.evaluation.point_p_k[i]), cv::FILLED);
  draw_obstacles(plot, view, room.obstacles);
  cv::rectangle(plot, view.px(room.volume.min), view.px(room.volume.max), kVolume, 2);
  const double length = 0.5 * (room.volume.max - room.volume.min).norm();
  for (const auto& camera : input.cameras) draw_frustum(plot, view, camera, length);
}

// The cameras over everything else, on the whole image so that a name by the edge is not cut.
void draw_cameras(cv::Mat& image, const View& view, const std::vector<PlannedCamera>& cameras) {
  for (const auto& camera : cameras) {
    const cv::Point at = view.px(camera.model.center_world()) + view.frame.area.tl();
    cv::circle(image, at, 5, kCamera, cv::FILLED, cv::LINE_AA);
    cv::putText(image, camera.id, at + cv::Point(6, -6), cv::FONT_HERSHEY_SIMPLEX, 0.4, kCamera, 1,
                cv::LINE_AA);
  }
}

cv::Mat draw_view(const ReportInput& input, int a, int b, const std::string& caption) {
  const auto [lo, hi] = content_bounds(input, a, b);
  const View view(a, b, lo, hi);
  cv::Mat image(view.image_size, CV_8UC3, kWhite);
  cv::Mat plot = image(view.frame.area);  // drawing on it clips to the plot area
  draw_scene(plot, view, input);
  draw_cameras(image, view, input.cameras);
  const char* axes = "xyz";
  const auto& area = view.frame.area;
  draw_axes(image, view.frame, linear_ticks(view.frame.x_lo, view.frame.x_hi, std::max(2, area.width / 80)),
            linear_ticks(view.frame.y_lo, view.frame.y_hi, std::max(2, area.height / 70)),
            {std::string(1, axes[a]) + " (m)", std::string(1, axes[b]) + " (m)"});
  const std::string label = caption + " (" + axes[a] + " right, " + axes[b] +
                            " up; green: P(>=" + std::to_string(input.metric.k_cameras) +
                            " cameras) = 1, red: <= 0.5)";
  cv::putText(image, label, {10, 22}, cv::FONT_HERSHEY_SIMPLEX, 0.5, kBlack, 1, cv::LINE_AA);
  return image;
}

// How the report states an objective's values: the figure it is, its unit and the factor from
// metres (docs/planner.md, "Objectives").
struct ObjectiveUnit {
  const char* unit;
  double per_metre;
  const char* meaning;
};

ObjectiveUnit objective_unit(const std::string& objective) {
  if (objective == "tracker_rmse")
    return {"mm", 1000.0,
            "the predicted tracker RMSE with gaps charged: the root mean square, over every (point, occluder "
            "plane) sample, of the position error the tracker is expected to make there: the triangulation "
            "error where two or more cameras see the point, tracker.publish_max_sigma_m / 2 (10 mm by "
            "default) where fewer do"};
  return {"m", 1.0,
          "the seed's quality q (eq. 4.8): the RMS over the points of their position uncertainty under the "
          "occluder planes, an unconstrained direction counting metric.unseen_m"};
}

cv::Mat draw_history(const std::vector<double>& history, const std::string& objective) {
  constexpr int kWidth = 900, kHeight = 400;
  cv::Mat image(kHeight, kWidth, CV_8UC3, kWhite);
  const auto [lowest, highest] = std::minmax_element(history.begin(), history.end());
  // Millimetre-sized values (tracker_rmse's, a good plan's q) read in millimetres.
  const double per_unit = *highest < 0.1 ? 1000.0 : 1.0;
  const std::string unit_name = per_unit == 1000.0 ? "mm" : "m";
  const double top = std::log10(std::max(*highest * per_unit, 1e-9));
  const double bottom = std::log10(std::max(*lowest * per_unit, 1e-9));
  const double pad = std::max(0.05 * (top - bottom), 0.02);
  PlotFrame frame;
  frame.area = cv::Rect(95, 40, kWidth - 95 - 25, kHeight - 40 - 75);
  frame.x_lo = 1;  // sweeps are counted from 1
  frame.x_hi = std::max(2.0, static_cast<double>(history.size()));
  frame.y_lo = bottom - pad;
  frame.y_hi = top + pad;
  frame.log_y = true;
  std::vector<cv::Point> line;
  for (std::size_t i = 0; i < history.size(); ++i)
    line.emplace_back(frame.column(static_cast<double>(i + 1)), frame.row(history[i] * per_unit));
  cv::polylines(image, line, false, kCamera, 2, cv::LINE_AA);
  std::vector<Tick> sweeps;
  for (const Tick& tick : linear_ticks(frame.x_lo, frame.x_hi, 10))
    if (tick.value == std::round(tick.value)) sweeps.push_back(tick);
  draw_axes(
      image, frame, sweeps, log_ticks(std::pow(10.0, frame.y_lo), std::pow(10.0, frame.y_hi)),
      {"sweep over the cameras (iteration of the search)", objective + " (" + unit_name + ", log scale)"});
  char text[200];
  std::snprintf(text, sizeof text, "best %s after each sweep of the search: %.4g %s -> %.4g %s",
                objective.c_str(), history.front() * per_unit, unit_name.c_str(), history.back() * per_unit,
                unit_name.c_str());
  cv::putText(image, text, {10, 22}, cv::FONT_HERSHEY_SIMPLEX, 0.5, kBlack, 1, cv::LINE_AA);
  return image;
}

std::string base64(const std::vector<unsigned char>& bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const unsigned v = (bytes[i] << 16) | ((i + 1 < bytes.size() ? bytes[i + 1] : 0) << 8) |
                       (i + 2 < bytes.size() ? bytes[i + 2] : 0);
    out += table[(v >> 18) & 63];
    out += table[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? table[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? table[v & 63] : '=';
  }
  return out;
}

std::string write_png(const cv::Mat& image, const fs::path& path) {
  const std::vector<std::uint8_t> bytes = encode_png(view_of(image));
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error(path.string() + ": cannot write");
  return "data:image/png;base64," + base64(bytes);
}

// Share of the sample points a camera sees through the static scene.
double share_seen(const PlannedCamera& camera, const ReportInput& input) {
  MetricOptions single = input.metric;
  single.k_cameras = 1;
  SampleSet plain = *input.samples;
  plain.normals.clear();
  const std::vector<PlannedCamera> one = {camera};
  return evaluate(one, plain, input.room->obstacles, single).p_at_least_k;
}

// The objective with all cameras, in metres.
double objective_with_all(const ReportInput& input) {
  return input.objective == "tracker_rmse" ? input.tracking.rmse_gaps_charged_m : input.evaluation.quality;
}

// Per camera: lens, position, view direction, share of the points seen, and the objective without
// it (the removal cost) in the objective's unit, with what that objective is.
void camera_table(const ReportInput& input, std::ostringstream& html) {
  const ObjectiveUnit unit = objective_unit(input.objective);
  const double with_all = objective_with_all(input) * unit.per_metre;
  char line[400];
  html << "<p>Objective <b>" << input.objective << "</b>, in " << unit.unit << ": " << unit.meaning << ". ";
  std::snprintf(line, sizeof line, "With all cameras: <b>%#.3g %s</b>.", with_all, unit.unit);
  html << line
       << " The last columns give it without each camera: the camera whose removal raises it least is "
          "the one to drop first.</p>\n";
  html << "<table><tr><th>camera</th><th>lens</th><th>x (m)</th><th>y (m)</th><th>z (m)</th><th>view dir</th>"
          "<th>points seen</th><th>"
       << input.objective << " without it (" << unit.unit << ")</th><th>change</th></tr>\n";
  for (std::size_t c = 0; c < input.cameras.size(); ++c) {
    const auto& camera = input.cameras[c];
    const Eigen::Vector3d p = camera.model.center_world();
    const Eigen::Vector3d d = camera.model.T_world_cam().rotation().col(2);
    std::snprintf(
        line, sizeof line,
        "<tr><td>%s</td><td>%s</td><td>%.3f</td><td>%.3f</td><td>%.3f</td><td>(%.2f, %.2f, %.2f)</td>"
        "<td>%.1f%%</td>",
        camera.id.c_str(), camera.lens.c_str(), p.x(), p.y(), p.z(), d.x(), d.y(), d.z(),
        100.0 * share_seen(camera, input));
    html << line;
    if (c < input.removal_costs.size()) {
      const double without = input.removal_costs[c] * unit.per_metre;
      std::snprintf(line, sizeof line, "<td>%#.3g</td><td>%+.1f%%</td></tr>\n", without,
                    with_all > 0 ? 100.0 * (without / with_all - 1.0) : 0.0);
      html << line;
    } else {
      html << "<td></td><td></td></tr>\n";
    }
  }
  html << "</table>\n";
}

}  // namespace

void write_report(const ReportInput& input, const fs::path& dir) {
  fs::create_directories(dir);
  const std::string top = write_png(draw_view(input, 0, 1, "top view"), dir / "top.png");
  const std::string side = write_png(draw_view(input, 0, 2, "side view"), dir / "side.png");
  std::string history;
  if (!input.history.empty())
    history = write_png(draw_history(input.history, input.objective), dir / "history.png");

  std::ostringstream html;
  html << "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>" << input.title
       << "</title><style>body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}"
          "td,th{border:1px solid #bbb;padding:4px "
          "8px;text-align:right}th{background:#eee}</style></head><body>\n";
  html << "<h1>" << input.title << "</h1>\n<p>" << input.notes << "</p>\n";
  char line[400];
  std::snprintf(
      line, sizeof line,
      "<p>Quality (eq. 4.8, lower is better): <b>%.4g m</b>; resolution only (no dynamic occluder): %.4g m; "
      "P(at least %d cameras see a point): <b>%.4f</b>.</p>\n",
      input.evaluation.quality, input.evaluation.resolution_only, input.metric.k_cameras,
      input.evaluation.p_at_least_k);
  html << line;
  std::snprintf(
      line, sizeof line,
      "<p>Predicted tracker RMSE: <b>%.3g mm</b> (%.3g mm with gaps charged); marker-time seen by one "
      "camera %.4f, by two %.4f (with a rival marker in the epipolar band %.4f).</p>\n",
      1000.0 * input.tracking.rmse_m, 1000.0 * input.tracking.rmse_gaps_charged_m,
      input.tracking.one_view_share, input.tracking.two_view_share, input.tracking.ambiguous_share);
  html << line << "<p>Cameras seeing a point (over points and occluder planes):";
  for (std::size_t n = 0; n < input.evaluation.visible_histogram.size(); ++n) {
    std::snprintf(line, sizeof line, " %zu: %.3f;", n, input.evaluation.visible_histogram[n]);
    html << line;
  }
  html << "</p>\n";
  camera_table(input, html);
  html << "<h2>Top view</h2><img src=\"" << top << "\">\n<h2>Side view</h2><img src=\"" << side << "\">\n";
  if (!history.empty()) html << "<h2>Optimisation</h2><img src=\"" << history << "\">\n";
  html << "</body></html>\n";
  std::ofstream out(dir / "report.html", std::ios::trunc);
  out << html.str();
  if (!out) throw std::runtime_error((dir / "report.html").string() + ": cannot write");
}

}  // namespace panoptes::planner
