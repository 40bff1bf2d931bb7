// SPDX-License-Identifier: Apache-2.0
#include "panoptes/sim_ptz/sim_ptz.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/errors.h"
#include "panoptes/pgm.h"
#include "panoptes/ptz/ptz_file.h"
#include "panoptes/simulator.h"

namespace fs = std::filesystem;

namespace panoptes::sim_tool {

namespace {

Eigen::Vector3d parse_offset(const std::string& text) {
  std::vector<double> values;
  std::stringstream stream(text);
  for (std::string item; std::getline(stream, item, ',');) {
    try {
      values.push_back(std::stod(item));
    } catch (const std::exception&) {
      values.clear();
      break;
    }
  }
  if (values.size() != 3) throw ConfigError("--offset", "", "expected x,y,z in metres, got '" + text + "'");
  return {values[0], values[1], values[2]};
}

std::vector<ptz::PtzCommand> read_commands(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path, "", "cannot read the commands file");
  std::vector<ptz::PtzCommand> commands;
  int line_number = 0, bad = 0;
  std::string first_error;
  for (std::string line; std::getline(in, line);) {
    ++line_number;
    if (line.empty()) continue;
    std::string error;
    if (auto command = ptz::command_from_json(line, error)) {
      commands.push_back(*command);
    } else if (bad++ == 0) {
      first_error = "line " + std::to_string(line_number) + ": " + error;
    }
  }
  if (bad > 0)
    std::cerr << "panoptes_sim ptz: " << path << ": " << bad << " bad line(s) ignored, first " << first_error
              << "\n";
  if (commands.empty()) throw ConfigError(path, "", "no commands");
  std::stable_sort(commands.begin(), commands.end(), [](const ptz::PtzCommand& a, const ptz::PtzCommand& b) {
    return a.issued_ns < b.issued_ns;
  });
  return commands;
}

std::size_t marker_index(const Scene& scene, const std::string& name, const std::string& scene_file) {
  const auto& names = scene.marker_names();
  const auto found = std::find(names.begin(), names.end(), name);
  if (found != names.end()) return static_cast<std::size_t>(found - names.begin());
  std::string known;
  for (const auto& n : names) known += (known.empty() ? "" : ", ") + n;
  throw ConfigError(scene_file, "--marker", "no marker '" + name + "' (the scene has: " + known + ")");
}

// The narrow view at reduced size: the scene's markers as discs, the followed point as a cross,
// the central half of the image as a grey frame.
Image render_view(const ptz::PtzModel& model, const ptz::PtzPose& pose,
                  const std::vector<MarkerTruth>& markers, const Scene& scene,
                  const Eigen::Vector3d& followed, double scale) {
  Image image(std::max(16, static_cast<int>(model.width * scale)),
              std::max(16, static_cast<int>(model.height * scale)), 8);
  std::fill(image.data.begin(), image.data.end(), std::uint8_t{16});
  const auto put = [&](int x, int y, std::uint8_t value) {
    if (x >= 0 && y >= 0 && x < image.width && y < image.height) image.row8(y)[x] = value;
  };
  const int x0 = image.width / 4, x1 = 3 * image.width / 4, y0 = image.height / 4, y1 = 3 * image.height / 4;
  for (int x = x0; x <= x1; ++x) put(x, y0, 80), put(x, y1, 80);
  for (int y = y0; y <= y1; ++y) put(x0, y, 80), put(x1, y, 80);
  const double focal = 0.5 * model.width / std::tan(0.5 * pose.fov) * scale;
  for (std::size_t i = 0; i < markers.size(); ++i) {
    if (!markers[i].valid) continue;
    const auto pixel = ptz::image_point(model, pose, markers[i].p);
    if (!pixel) continue;
    const double depth = std::max(1e-3, (markers[i].p - model.position).norm());
    const double radius = std::max(1.5, scene.marker_radius(i) * focal / depth);
    const double cx = pixel->x() * scale, cy = pixel->y() * scale;
    for (int y = static_cast<int>(cy - radius); y <= static_cast<int>(cy + radius) + 1; ++y)
      for (int x = static_cast<int>(cx - radius); x <= static_cast<int>(cx + radius) + 1; ++x)
        if (std::hypot(x - cx, y - cy) <= radius) put(x, y, 255);
  }
  // The followed point as a head-sized grey disc (radius 0.1 m) with a cross at its centre.
  if (const auto pixel = ptz::image_point(model, pose, followed)) {
    const double cx = pixel->x() * scale, cy = pixel->y() * scale;
    const double radius = 0.1 * focal / std::max(1e-3, (followed - model.position).norm());
    for (int y = static_cast<int>(cy - radius); y <= static_cast<int>(cy + radius) + 1; ++y)
      for (int x = static_cast<int>(cx - radius); x <= static_cast<int>(cx + radius) + 1; ++x)
        if (std::hypot(x - cx, y - cy) <= radius) put(x, y, 110);
    for (int d = -6; d <= 6; ++d)
      put(static_cast<int>(cx) + d, static_cast<int>(cy), 230),
          put(static_cast<int>(cx), static_cast<int>(cy) + d, 230);
  }
  return image;
}

struct Framing {
  std::int64_t samples = 0;
  std::int64_t in_image = 0;
  std::int64_t central_half = 0;
  std::vector<double> offset_fraction;  // |offset from the centre| / half the image width
};

}  // namespace

CLI::App* add_ptz_subcommand(CLI::App& app, PtzRunOptions& options) {
  CLI::App* ptz = app.add_subcommand(
      "ptz",
      "Drive a simulated pan/tilt/zoom camera with recorded commands and measure how it frames a marker");
  ptz->add_option("--scene", options.scene, "Scene file (YAML): the truth the camera looks at")->required();
  ptz->add_option("--ptz", options.ptz, "PTZ camera file (YAML, docs/ptz.md)")->required();
  ptz->add_option("--commands", options.commands, "Commands (JSON Lines, as ptz_guide writes them)")
      ->required();
  ptz->add_option("--marker", options.marker, "Scene marker the camera should frame")->required();
  ptz->add_option("--offset", options.offset,
                  "Added to the marker: the framed point, x,y,z m (e.g. marker -> head)");
  ptz->add_option("--skip", options.skip_s, "Seconds after the first command not measured (acquisition)")
      ->check(CLI::Range(0.0, 3600.0));
  ptz->add_option("--out-frames", options.out_frames,
                  "Directory for PGM images of the narrow view (none if empty)");
  ptz->add_option("--frames-every", options.frames_every_s, "Seconds between written images")
      ->check(CLI::Range(0.001, 3600.0));
  ptz->add_option("--frame-scale", options.frame_scale, "Size of the written images relative to the camera's")
      ->check(CLI::Range(0.05, 1.0));
  ptz->add_option("--summary-json", options.summary_json, "Also write the summary to this file");
  ptz->add_option("--epoch-ns", options.epoch_ns, "Absolute stamp of scene time 0 (ns)");
  return ptz;
}

int run_ptz(const PtzRunOptions& options) {
  const ptz::PtzModel model = ptz::load_ptz_model(options.ptz);
  const Scene scene = Scene::load(options.scene);
  const std::vector<ptz::PtzCommand> commands = read_commands(options.commands);
  const std::size_t marker = marker_index(scene, options.marker, options.scene);
  const Eigen::Vector3d offset = parse_offset(options.offset);
  if (!options.out_frames.empty()) fs::create_directories(options.out_frames);

  const TimeNs start = std::max<TimeNs>(0, commands.front().issued_ns - options.epoch_ns);
  const TimeNs end = std::min(scene.duration_ns(), commands.back().issued_ns - options.epoch_ns);
  const TimeNs measured_from = start + seconds_to_ns(options.skip_s);
  const auto followed_at = [&](TimeNs t, std::vector<MarkerTruth>& markers) {
    markers = scene.markers_at(t);
    return markers[marker].p + offset;
  };
  std::vector<MarkerTruth> markers;
  ptz::PtzPose initial = ptz::aim_at(model, followed_at(start, markers));
  initial.fov = commands.front().fov;
  ptz::PtzSimulator head(model, initial, start + options.epoch_ns);

  Framing framing;
  std::size_t next_command = 0;
  const TimeNs frame_step = seconds_to_ns(options.frames_every_s);
  TimeNs next_frame = measured_from;
  int frames_written = 0;
  for (TimeNs t = start; t <= end; t += kNsPerMillisecond) {
    while (next_command < commands.size() && commands[next_command].issued_ns - options.epoch_ns <= t)
      head.send(commands[next_command++]);
    head.advance_to(t + options.epoch_ns);
    const Eigen::Vector3d followed = followed_at(t, markers);
    if (!markers[marker].valid || t < measured_from) continue;
    ++framing.samples;
    if (const auto pixel = ptz::image_point(model, head.pose(), followed)) {
      const Eigen::Vector2d from_centre = *pixel - Eigen::Vector2d(0.5 * model.width, 0.5 * model.height);
      framing.in_image +=
          std::abs(from_centre.x()) <= 0.5 * model.width && std::abs(from_centre.y()) <= 0.5 * model.height;
      framing.central_half +=
          std::abs(from_centre.x()) <= 0.25 * model.width && std::abs(from_centre.y()) <= 0.25 * model.height;
      framing.offset_fraction.push_back(from_centre.norm() / (0.5 * model.width));
    } else {
      framing.offset_fraction.push_back(1e9);
    }
    if (!options.out_frames.empty() && t >= next_frame) {
      char name[64];
      std::snprintf(name, sizeof name, "ptz_%06lld.pgm", static_cast<long long>(t / kNsPerMillisecond));
      write_pgm(render_view(model, head.pose(), markers, scene, followed, options.frame_scale),
                fs::path(options.out_frames) / name);
      ++frames_written;
      next_frame += frame_step;
    }
  }
  if (framing.samples == 0)
    throw ConfigError(options.commands, "", "the commands cover no measured time of the scene");
  std::vector<double> sorted = framing.offset_fraction;
  std::sort(sorted.begin(), sorted.end());
  const auto share = [&](std::int64_t n) {
    return static_cast<double>(n) / static_cast<double>(framing.samples);
  };
  const nlohmann::json summary = {{"ptz", model.name},
                                  {"marker", options.marker},
                                  {"commands", commands.size()},
                                  {"measured_s", static_cast<double>(framing.samples) * 1e-3},
                                  {"central_half_fraction", share(framing.central_half)},
                                  {"in_image_fraction", share(framing.in_image)},
                                  {"offset_p50", sorted[sorted.size() / 2]},
                                  {"offset_p95", sorted[sorted.size() * 95 / 100]},
                                  {"frames_written", frames_written}};
  std::printf("%s\n", summary.dump().c_str());
  if (!options.summary_json.empty()) {
    std::ofstream out(options.summary_json);
    out << summary.dump(2) << "\n";
    if (!out) throw std::runtime_error(options.summary_json + ": cannot write");
  }
  return 0;
}

}  // namespace panoptes::sim_tool
