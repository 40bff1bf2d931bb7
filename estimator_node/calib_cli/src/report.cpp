// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calib/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "panoptes/calibration.h"
#include "panoptes/calibration_file.h"
#include "panoptes/image_coverage.h"
#include "panoptes/image_file_cv.h"

namespace panoptes::calib {

namespace {

std::string format(const char* pattern, auto... values) {
  char buffer[512];
  std::snprintf(buffer, sizeof(buffer), pattern, values...);
  return buffer;
}

// Green (0 px) to red (>= 1 px).
cv::Scalar error_colour(double error_px) {
  const double a = std::clamp(error_px, 0.0, 1.0);
  return {0, 255 * (1 - a), 255 * a};
}

const cv::Scalar kPalette[] = {{230, 159, 0}, {86, 180, 233}, {0, 158, 115},   {240, 228, 66},
                               {0, 114, 178}, {213, 94, 0},   {204, 121, 167}, {120, 120, 120}};

void write_png(const std::filesystem::path& path, const cv::Mat& image,
               std::vector<std::filesystem::path>& written) {
  panoptes::write_png(path, view_of(image));
  written.push_back(path);
}

std::filesystem::path sibling(const std::filesystem::path& out_yaml, const std::string& suffix) {
  return out_yaml.parent_path() / (out_yaml.stem().string() + suffix);
}

}  // namespace

double image_coverage(const SolveResult& result, int camera) {
  const auto& k = result.cameras[static_cast<std::size_t>(camera)].intrinsics;
  if (k.width <= 0 || k.height <= 0) return 0.0;
  ImageCoverage grid;
  grid.set_size(k.width, k.height);
  for (const auto& r : result.residuals) {
    if (r.camera == camera) grid.add(r.observed.x(), r.observed.y());
  }
  return grid.fraction();
}

namespace {

std::string raw_error_line(const char* name, const ErrorStats& all, const ErrorStats& inliers) {
  return format(
      "%s: all %d observations mean %.3f median %.3f (%.1f%% within 5 px); inliers (<= %.0f px) %d "
      "observations mean %.3f median %.3f\n",
      name, all.count, all.mean_px, all.median_px, 100 * all.within_5px, kRawInlierPx, inliers.count,
      inliers.mean_px, inliers.median_px);
}

// Per camera: how well the adjustment separates focal length and depth (solve_diagnostics.h).
std::string focal_depth_lines(const SolveResult& result) {
  bool any_free = false, any = false;
  for (const auto& camera : result.cameras) {
    any = any || camera.focal_depth.available;
    any_free = any_free || camera.focal_depth.focal_free;
  }
  if (!any) return "";
  std::ostringstream out;
  out << "focal length and depth (1-sigma from the adjustment; depth = distance to the wand volume's "
         "centre)"
      << (any_free ? "" : ", intrinsics fixed")
      << (result.metric ? ":\n"
                        : "; UNSCALED: m and mm are units and thousandths of the first pair's baseline:\n")
      << "camera        depth m  depth sigma mm  position sigma mm  focal sigma px  corr f/depth  "
         "1% focal: depth shift mm  rms rise px\n";
  for (const auto& camera : result.cameras) {
    const auto& stats = camera.focal_depth;
    if (!stats.available) continue;
    out << format("%-12s  %7.3f  %14.3f  %17.3f", camera.id.c_str(), stats.depth_m, stats.depth_sigma_mm,
                  stats.position_sigma_mm);
    if (stats.focal_free)
      out << format("  %14.3f  %+12.3f  %24.2f  %11.4f\n", stats.focal_sigma_px, stats.correlation,
                    stats.shift_per_percent_mm, stats.rms_increase_per_percent_px);
    else
      out << "               -             -                         -            -\n";
  }
  return out.str();
}

}  // namespace

std::string report_summary(const SolveResult& result) {
  std::ostringstream out;
  out << format("calibrated %d of %zu cameras (reference %s) in %.1f s, %d iterations\n",
                result.calibrated_count(), result.cameras.size(), result.reference_camera.c_str(),
                result.seconds, result.iterations);
  // The headline: raw frames, 2D, the figure other tools report.
  out << raw_error_line("raw-frame reprojection error, 2D, px", result.raw_all, result.raw_inliers);
  if (!result.convergence.empty())
    out << (result.converged ? "bundle adjustment: " : "WARNING: bundle adjustment did not converge: ")
        << result.convergence << "\n";
  if (!result.intrinsics_refined.empty()) {
    out << "intrinsics refined"
        << (result.intrinsics_refined == "--refine-intrinsics" ? " (" : " automatically (")
        << result.intrinsics_refined << "):";
    for (const auto& camera : result.cameras) {
      if (!camera.intrinsics_refined || !camera.T_world_cam) continue;
      const auto& given = camera.given_intrinsics;
      const auto& k = camera.intrinsics;
      out << format(" %s f %.0f->%.1f px", camera.id.c_str(), 0.5 * (given.fx + given.fy),
                    0.5 * (k.fx + k.fy));
      if (k.cx != given.cx || k.cy != given.cy)
        out << format(" c (%.1f, %.1f)->(%.1f, %.1f) px", given.cx, given.cy, k.cx, k.cy);
    }
    out << "\n";
  }
  if (!result.intrinsics_declined.empty()) out << "intrinsics " << result.intrinsics_declined << "\n";
  out << "camera        state       raw obs  raw mean px  raw median px  within 5 px  raw rms px/axis  "
         "sample rms px  max px  offset ms  coverage\n";
  for (std::size_t c = 0; c < result.cameras.size(); ++c) {
    const auto& camera = result.cameras[c];
    out << format("%-12s  %-10s  %7d  %11.3f  %13.3f  %10.1f%%  %15.3f  %13.3f  %6.2f  %9.3f  %7.0f%%\n",
                  camera.id.c_str(), camera.T_world_cam ? "calibrated" : "FAILED", camera.raw_all.count,
                  camera.raw_all.mean_px, camera.raw_all.median_px, 100 * camera.raw_all.within_5px,
                  camera.raw_rms_axis_px, camera.rms_px, camera.max_px, camera.time_offset_s * 1e3,
                  100 * image_coverage(result, static_cast<int>(c)));
  }
  out << format(
      "also: raw frames %.3f px RMS per axis over the inliers (compare with the centroid noise); the "
      "adjustment's samples (%s) %.3f px RMS 2D\n",
      result.raw_rms_axis_px, result.synchronised ? "the frames themselves" : "interpolated between frames",
      result.rms_px);
  if (result.lengths.count > 0)
    out << format(
        "wand length (triangulated without the length constraint, %d samples): error mean %+.3f mm, "
        "median %+.3f mm, RMS %.3f mm (the reprojection error predicts %.3f mm), sigma %.3f mm, max %.3f "
        "mm\n",
        result.lengths.count, result.lengths.mean_error_mm, result.lengths.median_error_mm,
        result.lengths.rms_error_mm, result.predicted_length_rms_mm, result.lengths.sigma_mm,
        result.lengths.max_abs_error_mm);
  out << focal_depth_lines(result);
  if (!result.metric && result.calibrated_count() > 0)
    out << "UNSCALED: a single light gives no metric scale; set it with `calibrate world --lframe <x arm "
           "m>,<y arm m>`\n";
  if (result.bar_labels)
    out << format(
        "bar ends (they look alike): %d label runs, %d reversed to agree across cameras, %d unrelated "
        "runs dropped (%d frames); %d of %d votes against the labelling\n",
        result.bar_labels->runs, result.bar_labels->flipped_runs, result.bar_labels->dropped_runs,
        result.bar_labels->dropped_frames, result.bar_labels->conflicting_votes, result.bar_labels->votes);
  for (const auto& warning : result.warnings) out << "WARNING: " << warning << "\n";
  for (const auto& error : result.errors) out << "error: " << error << "\n";
  return out.str();
}

std::string calibration_yaml(const SolveResult& result) {
  SystemCalibration calibration;
  std::ostringstream header;
  header << "# Panoptes wand calibration: " << result.calibrated_count() << " of " << result.cameras.size()
         << " cameras calibrated, reference " << result.reference_camera << ".\n";
  if (!result.metric)
    header << kUnscaledMarker
           << ": a single light gives no metric scale; positions are in units of the first camera pair's "
              "baseline.\n# Set the scale with `estimator_node calibrate world --lframe <x arm m>,<y arm m>` "
              "(docs/calibration.md, \"Single LED\").\n";
  for (const auto& camera : result.cameras) {
    calibration.cameras.push_back({camera.id, camera.intrinsics, camera.T_world_cam, false, false, {}});
    if (!camera.T_world_cam)
      header << "# NOT CALIBRATED (no T_world_cam): " << camera.id << ": " << camera.failure << "\n";
  }
  return header.str() + calibration_to_yaml(calibration);
}

bool calibration_file_is_unscaled(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot read");
  const std::string marker = kUnscaledMarker;
  for (std::string line; std::getline(in, line);) {
    if (line.empty()) continue;
    if (line.front() != '#') break;  // the leading comment block only
    if (line.compare(0, marker.size(), marker) == 0) return true;
  }
  return false;
}

namespace {

// The summary and the pairwise relative poses as text.
void write_text_report(const SolveResult& result, const std::filesystem::path& out_yaml,
                       std::vector<std::filesystem::path>& written) {
  const auto text_path = sibling(out_yaml, ".report.txt");
  std::ofstream text(text_path);
  if (!text) throw std::runtime_error(text_path.string() + ": cannot write");
  text << report_summary(result);
  text << "\npairwise relative poses (seed 003 §3.3.1 ranking):\n";
  for (const auto& edge : result.edges)
    text << format("  %s-%s: %d common samples, %d inliers, residual %.3f px, scale %.4f m%s\n",
                   edge.camera_a.c_str(), edge.camera_b.c_str(), edge.samples, edge.inliers, edge.residual_px,
                   edge.scale, edge.used ? ", used" : "");
  written.push_back(text_path);
}

nlohmann::json stats_json(const ErrorStats& stats) {
  return {{"count", stats.count},
          {"mean_px", stats.mean_px},
          {"median_px", stats.median_px},
          {"rms_axis_px", stats.rms_axis_px},
          {"within_5px", stats.within_5px}};
}

nlohmann::json focal_depth_json(const FocalDepthStats& stats) {
  nlohmann::json json{{"depth_m", stats.depth_m},
                      {"depth_sigma_mm", stats.depth_sigma_mm},
                      {"position_sigma_mm", stats.position_sigma_mm},
                      {"focal_refined", stats.focal_free}};
  if (stats.focal_free) {
    json["focal_sigma_px"] = stats.focal_sigma_px;
    json["correlation"] = stats.correlation;
    json["depth_shift_per_percent_focal_mm"] = stats.shift_per_percent_mm;
    json["rms_rise_per_percent_focal_px"] = stats.rms_increase_per_percent_px;
  }
  return json;
}

// Everything a script may want to check, machine-readable.
nlohmann::json report_json(const SolveResult& result) {
  nlohmann::json json;
  json["reference_camera"] = result.reference_camera;
  json["rms_px"] = result.rms_px;
  json["raw_rms_axis_px"] = result.raw_rms_axis_px;
  json["raw_frame_error_2d_px"] = {{"all", stats_json(result.raw_all)},
                                   {"inliers", stats_json(result.raw_inliers)}};
  json["converged"] = result.converged;
  json["convergence"] = result.convergence;
  json["intrinsics_refined"] = result.intrinsics_refined;
  json["intrinsics_declined"] = result.intrinsics_declined;
  json["synchronised"] = result.synchronised;
  json["seconds"] = result.seconds;
  json["iterations"] = result.iterations;
  json["wand_length"] = {{"samples", result.lengths.count},
                         {"mean_error_mm", result.lengths.mean_error_mm},
                         {"sigma_mm", result.lengths.sigma_mm},
                         {"median_error_mm", result.lengths.median_error_mm},
                         {"rms_error_mm", result.lengths.rms_error_mm},
                         {"predicted_rms_error_mm", result.predicted_length_rms_mm},
                         {"max_abs_error_mm", result.lengths.max_abs_error_mm}};
  json["warnings"] = result.warnings;
  json["metric"] = result.metric;
  if (result.bar_labels) {
    const auto& labels = *result.bar_labels;
    json["bar_labels"] = {{"runs", labels.runs},
                          {"reversed_runs", labels.flipped_runs},
                          {"dropped_runs", labels.dropped_runs},
                          {"dropped_frames", labels.dropped_frames},
                          {"camera_pairs", labels.camera_pairs},
                          {"votes", labels.votes},
                          {"conflicting_votes", labels.conflicting_votes}};
  }
  json["errors"] = result.errors;
  json["cameras"] = nlohmann::json::array();
  for (std::size_t c = 0; c < result.cameras.size(); ++c) {
    const auto& camera = result.cameras[c];
    nlohmann::json item{{"id", camera.id},
                        {"calibrated", camera.T_world_cam.has_value()},
                        {"failure", camera.failure},
                        {"wand_frames", camera.wand_frames},
                        {"observations", camera.observations},
                        {"rms_px", camera.rms_px},
                        {"max_px", camera.max_px},
                        {"raw_rms_axis_px", camera.raw_rms_axis_px},
                        {"raw_frame_error_2d_px",
                         {{"all", stats_json(camera.raw_all)}, {"inliers", stats_json(camera.raw_inliers)}}},
                        {"intrinsics_refined", camera.intrinsics_refined},
                        {"time_offset_ms", camera.time_offset_s * 1e3},
                        {"coverage", image_coverage(result, static_cast<int>(c))},
                        {"fx", camera.intrinsics.fx},
                        {"fy", camera.intrinsics.fy},
                        {"cx", camera.intrinsics.cx},
                        {"cy", camera.intrinsics.cy},
                        {"distortion", camera.intrinsics.distortion}};
    if (camera.focal_depth.available) item["focal_depth"] = focal_depth_json(camera.focal_depth);
    json["cameras"].push_back(item);
  }
  json["pairs"] = nlohmann::json::array();
  for (const auto& edge : result.edges)
    json["pairs"].push_back({{"a", edge.camera_a},
                             {"b", edge.camera_b},
                             {"samples", edge.samples},
                             {"inliers", edge.inliers},
                             {"residual_px", edge.residual_px},
                             {"scale", edge.scale},
                             {"used", edge.used}});
  return json;
}

void write_json_report(const SolveResult& result, const std::filesystem::path& out_yaml,
                       std::vector<std::filesystem::path>& written) {
  const nlohmann::json json = report_json(result);
  const auto json_path = sibling(out_yaml, ".report.json");
  std::ofstream out(json_path);
  if (!out) throw std::runtime_error(json_path.string() + ": cannot write");
  out << json.dump(2) << "\n";
  written.push_back(json_path);
}

// Coverage: where in each image the wand was seen, coloured by the residual.
void write_coverage_images(const SolveResult& result, const std::filesystem::path& out_yaml,
                           std::vector<std::filesystem::path>& written) {
  for (std::size_t c = 0; c < result.cameras.size(); ++c) {
    const auto& camera = result.cameras[c];
    const auto& k = camera.intrinsics;
    if (k.width <= 0 || k.height <= 0) continue;
    const double scale = 640.0 / std::max(k.width, k.height);
    cv::Mat image(static_cast<int>(k.height * scale) + 24, static_cast<int>(k.width * scale), CV_8UC3,
                  cv::Scalar(32, 32, 32));
    for (int i = 1; i < 8; ++i) {
      cv::line(image, {image.cols * i / 8, 0}, {image.cols * i / 8, image.rows - 24}, {64, 64, 64});
      cv::line(image, {0, (image.rows - 24) * i / 8}, {image.cols, (image.rows - 24) * i / 8}, {64, 64, 64});
    }
    for (const auto& r : result.residuals)
      if (r.camera == static_cast<int>(c))
        cv::circle(image,
                   {static_cast<int>(r.observed.x() * scale), static_cast<int>(r.observed.y() * scale)}, 1,
                   error_colour(r.error.norm()), cv::FILLED);
    cv::putText(image,
                format("%s  %s  coverage %.0f%%  rms %.3f px  (green 0 px .. red >= 1 px)", camera.id.c_str(),
                       camera.T_world_cam ? "calibrated" : "FAILED",
                       100 * image_coverage(result, static_cast<int>(c)), camera.rms_px),
                {4, image.rows - 7}, cv::FONT_HERSHEY_SIMPLEX, 0.4, {255, 255, 255});
    write_png(sibling(out_yaml, ".coverage_" + camera.id + ".png"), image, written);
  }
}

// Residuals over time, one colour per camera.
void write_residual_plot(const SolveResult& result, const std::filesystem::path& out_yaml,
                         std::vector<std::filesystem::path>& written) {
  if (result.residuals.empty()) return;
  const int width = 900, height = 360, margin = 40;
  cv::Mat plot(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  TimeNs t0 = result.residuals.front().t_ns, t1 = t0;
  double top = 0;
  for (const auto& r : result.residuals) {
    t0 = std::min(t0, r.t_ns);
    t1 = std::max(t1, r.t_ns);
    top = std::max(top, r.error.norm());
  }
  top = std::min(std::max(top, 0.1), 4.0 * std::max(result.rms_px, 0.05));
  for (const auto& r : result.residuals) {
    const double x = margin + (width - 2 * margin) * static_cast<double>(r.t_ns - t0) /
                                  std::max<double>(1.0, static_cast<double>(t1 - t0));
    const double y = height - margin - (height - 2 * margin) * std::min(1.0, r.error.norm() / top);
    cv::circle(plot, {static_cast<int>(x), static_cast<int>(y)}, 1, kPalette[r.camera % 8], cv::FILLED);
  }
  cv::rectangle(plot, {margin, margin}, {width - margin, height - margin}, {0, 0, 0});
  cv::putText(plot,
              format("reprojection error (px, 0..%.2f) over %.1f s; one colour per camera", top,
                     static_cast<double>(t1 - t0) * 1e-9),
              {margin, margin - 12}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0});
  write_png(sibling(out_yaml, ".residuals.png"), plot, written);
}

// Top view: cameras (with viewing direction) and the wand path.
void write_layout_view(const SolveResult& result, const std::filesystem::path& out_yaml,
                       std::vector<std::filesystem::path>& written) {
  const int size = 640;
  cv::Mat view(size, size, CV_8UC3, cv::Scalar(255, 255, 255));
  double lo_x = 1e9, hi_x = -1e9, lo_y = 1e9, hi_y = -1e9;
  const auto extend = [&](const Eigen::Vector3d& p) {
    lo_x = std::min(lo_x, p.x());
    hi_x = std::max(hi_x, p.x());
    lo_y = std::min(lo_y, p.y());
    hi_y = std::max(hi_y, p.y());
  };
  for (const auto& camera : result.cameras)
    if (camera.T_world_cam) extend(camera.T_world_cam->t);
  for (const auto& sample : result.samples) extend(sample.markers.front());
  if (hi_x > lo_x || hi_y > lo_y) {
    const double span = std::max(hi_x - lo_x, hi_y - lo_y) * 1.15 + 1e-6;
    // size is even, so size / 2.0 is the same centre the integer division gave.
    const auto pixel = [&](const Eigen::Vector3d& p) {
      return cv::Point(static_cast<int>(size / 2.0 + (p.x() - (lo_x + hi_x) / 2) / span * size),
                       static_cast<int>(size / 2.0 - (p.y() - (lo_y + hi_y) / 2) / span * size));
    };
    for (const auto& sample : result.samples)
      cv::circle(view, pixel(sample.markers.front()), 1, {180, 180, 180});
    for (const auto& camera : result.cameras) {
      if (!camera.T_world_cam) continue;
      const Eigen::Vector3d c = camera.T_world_cam->t;
      const Eigen::Vector3d forward = camera.T_world_cam->rotation().col(2);
      cv::arrowedLine(view, pixel(c), pixel(c + 0.4 * span / 4 * forward), {0, 0, 200}, 2);
      cv::putText(view, camera.id, pixel(c) + cv::Point(4, -4), cv::FONT_HERSHEY_SIMPLEX, 0.4, {0, 0, 0});
    }
    cv::putText(view, format("top view, %.2f m across; grey: wand path", span), {8, 16},
                cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0});
  }
  write_png(sibling(out_yaml, ".layout.png"), view, written);
}

}  // namespace

std::vector<std::filesystem::path> write_report(const SolveResult& result,
                                                const std::filesystem::path& out_yaml) {
  std::vector<std::filesystem::path> written;
  write_text_report(result, out_yaml, written);
  write_json_report(result, out_yaml, written);
  write_coverage_images(result, out_yaml, written);
  write_residual_plot(result, out_yaml, written);
  write_layout_view(result, out_yaml, written);
  return written;
}

}  // namespace panoptes::calib
