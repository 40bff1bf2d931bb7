// SPDX-License-Identifier: Apache-2.0
// panoptes_source_probe: opens a camera_node frame source (any --source spec), reads frames and
// prints what a test needs to see of the source itself: one line per frame (with --frames-out),
// and at exit the source's counters in the line format camera_node prints:
//   source counters: name=value name=value ...   (keys sorted; stderr)
// Optionally calls restart() after a given number of frames.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "panoptes/camera/sources.h"
#include "panoptes/time.h"

namespace {

[[noreturn]] void usage(const std::string& problem) {
  std::fprintf(
      stderr,
      "panoptes_source_probe: %s\n"
      "usage: panoptes_source_probe --source SPEC [--frames N] [--timeout-ms T] [--restart-after K]\n"
      "         [--frames-out file.csv]\n",
      problem.c_str());
  std::exit(2);
}

}  // namespace

int main(int argc, char** argv) {
  std::string spec;
  std::string frames_out;
  long long frames = 100;
  long long restart_after = -1;
  panoptes::camera::SourceOptions options;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) usage("missing value after " + flag);
    const std::string value = argv[++i];
    try {
      if (flag == "--source")
        spec = value;
      else if (flag == "--frames")
        frames = std::stoll(value);
      else if (flag == "--timeout-ms")
        options.settings.timeout_ms = std::stod(value);
      else if (flag == "--reconnect-ms")
        options.settings.reconnect_interval_ms = std::stod(value);
      else if (flag == "--restart-after")
        restart_after = std::stoll(value);
      else if (flag == "--frames-out")
        frames_out = value;
      else
        usage("unknown option " + flag);
    } catch (const std::exception&) {
      usage("bad value '" + value + "' for " + flag);
    }
  }
  if (spec.empty()) usage("--source is required");
  options.max_frames = frames;

  std::unique_ptr<panoptes::camera::FrameSource> source;
  try {
    source = panoptes::camera::open_source(spec, options);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "panoptes_source_probe: %s\n", error.what());
    return 2;
  }
  std::FILE* out = frames_out.empty() ? nullptr : std::fopen(frames_out.c_str(), "w");
  if (out != nullptr) std::fprintf(out, "sequence,stamp_ns,arrival_ns,width,height,bits,exposure_us\n");
  long long count = 0;
  while (auto frame = source->next()) {
    ++count;
    if (out != nullptr) {
      std::fprintf(out, "%lld,%lld,%lld,%d,%d,%d,%.1f\n", static_cast<long long>(frame->sequence),
                   static_cast<long long>(frame->stamp_ns), static_cast<long long>(frame->arrival_ns),
                   frame->image.width, frame->image.height, frame->image.bits, frame->exposure_us);
    }
    if (count == restart_after) source->restart();
  }
  if (out != nullptr) std::fclose(out);
  std::string line = "source counters:";
  for (const auto& [name, value] : source->counters()) line += " " + name + "=" + std::to_string(value);
  std::fprintf(stderr, "panoptes_source_probe: read %lld frames\n%s\n", count, line.c_str());
  if (!source->last_error().empty()) std::fprintf(stderr, "last error: %s\n", source->last_error().c_str());
  return 0;
}
