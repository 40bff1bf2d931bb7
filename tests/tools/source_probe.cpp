// SPDX-License-Identifier: Apache-2.0
// panoptes_source_probe: opens a camera_node frame source (any --source spec), reads frames and
// prints what a test needs to see of the source itself: one line per frame (with --frames-out),
// and at exit the source's counters in the line format camera_node prints:
//   source counters: name=value name=value ...   (keys sorted; stderr)
// Optionally calls restart() after a given number of frames.
#include <cstdio>
#include <exception>
#include <string>

#include "panoptes/camera/sources.h"
#include "panoptes/cli.h"
#include "panoptes/process.h"
#include "panoptes/time.h"

namespace {

int run(int argc, char** argv) {
  std::string spec;
  std::string frames_out;
  long long frames = 100;
  long long restart_after = -1;
  panoptes::camera::SourceOptions options;
  CLI::App app{"panoptes_source_probe: reads frames from a camera_node frame source and prints its counters",
               "panoptes_source_probe"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  app.add_option("--source", spec, "source spec, as camera_node --source")->required();
  app.add_option("--frames", frames, "frames to read at most");
  app.add_option("--timeout-ms", options.settings.timeout_ms, "source settings: frame timeout, ms");
  app.add_option("--reconnect-ms", options.settings.reconnect_interval_ms,
                 "source settings: interval between reconnection attempts, ms");
  app.add_option("--restart-after", restart_after, "call restart() after this many frames")
      ->default_str("never");
  app.add_option("--frames-out", frames_out, "write one CSV line per frame to this file");
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv)) return *exit_code;
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

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_source_probe", [&] { return run(argc, argv); });
}
