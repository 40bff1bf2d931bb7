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
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace panoptes::planner {

namespace {

namespace fs = std::filesystem;

const cv::Scalar kBlack(0, 0, 0), kGrey(150, 150, 150), kObstacle(120, 120, 120), kVolume(200, 120, 40),
    kMount(60, 160, 60), kCamera(30, 30, 200);

// World axes (a, b) of a view onto an image with a margin; b grows upwards on the image.
struct View {
  int a = 0, b = 1;
  Eigen::Vector2d lo, hi;
  double scale = 1;
  int width = 900, height = 700, margin = 50;

  View(int axis_a, int axis_b, const Eigen::Vector2d& low, const Eigen::Vector2d& high)
      : a(axis_a), b(axis_b) {
    const Eigen::Vector2d pad = 0.05 * (high - low).cwiseMax(0.1);
    lo = low - pad;
    hi = high + pad;
    scale = std::min((width - 2 * margin) / (hi.x() - lo.x()), (height - 2 * margin) / (hi.y() - lo.y()));
  }
  cv::Point px(const Eigen::Vector3d& p) const {
    return {static_cast<int>(margin + (p[a] - lo.x()) * scale),
            static_cast<int>(height - margin - (p[b] - lo.y()) * scale)};
  }
};

void box_outline(cv::Mat& image, const View& view, const Box& box, const cv::Scalar& colour, int thickness) {
  Eigen::Vector3d lo = box.min, hi = box.max;
  cv::rectangle(image, view.px(lo), view.px(hi), colour, thickness);
}

// Green where at least k cameras see a point under every occluder, red where they do under half
// of the occluders or fewer.
cv::Scalar coverage_colour(double p) {
  p = std::clamp(2.0 * p - 1.0, 0.0, 1.0);
  return {60, 60 + 170 * p, 230 - 170 * p};
}

void draw_frustum(cv::Mat& image, const View& view, const PlannedCamera& camera, double length) {
  const auto& K = camera.model.intrinsics();
  const Eigen::Vector3d centre = camera.model.center_world();
  const std::array<Eigen::Vector2d, 4> corners = {Eigen::Vector2d(0, 0), Eigen::Vector2d(K.width, 0),
                                                  Eigen::Vector2d(K.width, K.height),
                                                  Eigen::Vector2d(0, K.height)};
  std::array<cv::Point, 4> far{};
  for (std::size_t i = 0; i < corners.size(); ++i) {
    far[i] = view.px(centre + length * camera.model.pixel_to_world_ray(corners[i]));
    cv::line(image, view.px(centre), far[i], kGrey, 1, cv::LINE_AA);
  }
  for (std::size_t i = 0; i < far.size(); ++i)
    cv::line(image, far[i], far[(i + 1) % far.size()], kGrey, 1, cv::LINE_AA);
  cv::circle(image, view.px(centre), 5, kCamera, cv::FILLED, cv::LINE_AA);
  cv::putText(image, camera.id, view.px(centre) + cv::Point(6, -6), cv::FONT_HERSHEY_SIMPLEX, 0.4, kCamera, 1,
              cv::LINE_AA);
}

cv::Mat draw_view(const ReportInput& input, int a, int b, const std::string& caption) {
  const Room& room = *input.room;
  Eigen::Vector2d lo(room.volume.min[a], room.volume.min[b]), hi(room.volume.max[a], room.volume.max[b]);
  const auto extend = [&](const Eigen::Vector3d& p) {
    lo = lo.cwiseMin(Eigen::Vector2d(p[a], p[b]));
    hi = hi.cwiseMax(Eigen::Vector2d(p[a], p[b]));
  };
  for (const auto& mount : room.mounts)
    for (const double s : {0.0, 1.0})
      for (const double t : {0.0, 1.0}) extend(mount.at(s, t));
  for (const auto& camera : input.cameras) extend(camera.model.center_world());
  const View view(a, b, lo, hi);
  cv::Mat image(view.height, view.width, CV_8UC3, cv::Scalar(255, 255, 255));
  for (const auto& mount : room.mounts) {
    std::vector<cv::Point> poly = {view.px(mount.at(0, 0)), view.px(mount.at(1, 0)), view.px(mount.at(1, 1)),
                                   view.px(mount.at(0, 1))};
    cv::polylines(image, poly, true, kMount, 1, cv::LINE_AA);
  }
  // Points drawn far-to-near along the hidden axis would need sorting; coverage is a mean anyway.
  const auto& points = input.samples->points;
  for (std::size_t i = 0; i < points.size(); ++i)
    cv::circle(image, view.px(points[i]), 2, coverage_colour(input.evaluation.point_p_k[i]), cv::FILLED);
  for (const auto& obstacle : room.obstacles) {
    cv::rectangle(image, view.px(obstacle.min), view.px(obstacle.max), kObstacle, cv::FILLED);
  }
  box_outline(image, view, room.volume, kVolume, 2);
  const double length = 0.5 * (room.volume.max - room.volume.min).norm();
  for (const auto& camera : input.cameras) draw_frustum(image, view, camera, length);
  const char* axes = "xyz";
  const std::string label = caption + " (" + axes[a] + " right, " + axes[b] +
                            " up; green: P(>=" + std::to_string(input.metric.k_cameras) +
                            " cameras) = 1, red: <= 0.5)";
  cv::putText(image, label, {10, 22}, cv::FONT_HERSHEY_SIMPLEX, 0.5, kBlack, 1, cv::LINE_AA);
  return image;
}

cv::Mat draw_history(const std::vector<double>& history, const std::string& objective) {
  cv::Mat image(360, 900, CV_8UC3, cv::Scalar(255, 255, 255));
  const int margin = 50;
  double lo = *std::min_element(history.begin(), history.end()),
         hi = *std::max_element(history.begin(), history.end());
  lo = std::log10(std::max(lo, 1e-9));
  hi = std::log10(std::max(hi, 1e-9));
  if (hi - lo < 1e-6) hi = lo + 1.0;
  std::vector<cv::Point> line;
  for (std::size_t i = 0; i < history.size(); ++i) {
    const double x =
        margin + (900.0 - 2 * margin) * static_cast<double>(i) / std::max<double>(1.0, history.size() - 1.0);
    const double y =
        360.0 - margin - (360.0 - 2 * margin) * (std::log10(std::max(history[i], 1e-9)) - lo) / (hi - lo);
    line.emplace_back(static_cast<int>(x), static_cast<int>(y));
  }
  cv::polylines(image, line, false, kCamera, 2, cv::LINE_AA);
  char text[160];
  std::snprintf(text, sizeof text, "best %s per sweep (log scale): %.4g m -> %.4g m", objective.c_str(),
                history.front(), history.back());
  cv::putText(image, text, {10, 22}, cv::FONT_HERSHEY_SIMPLEX, 0.5, kBlack, 1, cv::LINE_AA);
  cv::line(image, {margin, 360 - margin}, {900 - margin, 360 - margin}, kGrey);
  cv::line(image, {margin, margin}, {margin, 360 - margin}, kGrey);
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
  std::vector<unsigned char> bytes;
  if (!cv::imencode(".png", image, bytes)) throw std::runtime_error(path.string() + ": cannot encode PNG");
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
  html << "</p>\n<table><tr><th>camera</th><th>lens</th><th>x</th><th>y</th><th>z</th><th>view dir</th>"
          "<th>points seen</th><th>"
       << input.objective << " without it</th></tr>\n";
  for (std::size_t c = 0; c < input.cameras.size(); ++c) {
    const auto& camera = input.cameras[c];
    const Eigen::Vector3d p = camera.model.center_world();
    const Eigen::Vector3d d = camera.model.T_world_cam().rotation().col(2);
    std::snprintf(
        line, sizeof line,
        "<tr><td>%s</td><td>%s</td><td>%.3f</td><td>%.3f</td><td>%.3f</td><td>(%.2f, %.2f, %.2f)</td>"
        "<td>%.1f%%</td><td>%s</td></tr>\n",
        camera.id.c_str(), camera.lens.c_str(), p.x(), p.y(), p.z(), d.x(), d.y(), d.z(),
        100.0 * share_seen(camera, input),
        c < input.removal_costs.size() ? std::to_string(input.removal_costs[c]).c_str() : "");
    html << line;
  }
  html << "</table>\n<h2>Top view</h2><img src=\"" << top << "\">\n<h2>Side view</h2><img src=\"" << side
       << "\">\n";
  if (!history.empty()) html << "<h2>Optimisation</h2><img src=\"" << history << "\">\n";
  html << "</body></html>\n";
  std::ofstream out(dir / "report.html", std::ios::trunc);
  out << html.str();
  if (!out) throw std::runtime_error((dir / "report.html").string() + ": cannot write");
}

}  // namespace panoptes::planner
