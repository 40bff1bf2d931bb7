// SPDX-License-Identifier: Apache-2.0
// panoptes_fake_gige: a GigE Vision camera (Aravis's GVCP/GVSP fake) whose frames are synthetic IR
// images, Gaussian spots at known sub-pixel positions, with the truth of every frame written as a
// JSONL line {"frame", "device_ns", "ready_ns", "width", "height", "spots": [[x, y], ...]}. Optionally drops
// that fraction of stream packets.
//
// It listens on the given interface and answers discovery broadcasts: run it only inside a
// network namespace whose only interface is lo (tests/integration/test_aravis.sh does).
#include <arv.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <mutex>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "panoptes/cli.h"
#include "panoptes/process.h"
#include "spot_renderer.h"

namespace {

namespace testing = panoptes::camera::testing;

struct Options {
  std::string interface_name = "lo";
  std::string serial = "PANOPTES01";
  std::string truth_file;
  int width = 640;
  int height = 480;
  double frame_rate_hz = 50;
  double loss_ratio = 0;  // fraction of GVSP packets not sent
  int cell_px = 80;       // one spot per cell of this size
  double sigma_min_px = 1.2, sigma_max_px = 2.0;
  double amplitude_dn = 220;
  double background_dn = 10;
  double noise_dn = 1.0;
  std::uint64_t seed = 1;
  double duration_s = 0;  // 0 = until SIGINT/SIGTERM
};

std::atomic<bool> g_stop{false};
void request_stop(int /*signal*/) {
  g_stop.store(true);
}

// Called by the fake camera's thread for every frame, after it has set the frame id, timestamp
// and geometry of `buffer`.
struct Renderer {
  Options options;
  std::FILE* truth = nullptr;
  std::mutex mutex;

  void fill(ArvBuffer* buffer, ArvPixelFormat pixel_format) {
    const int width = arv_buffer_get_image_width(buffer);
    const int height = arv_buffer_get_image_height(buffer);
    const guint64 frame_id = arv_buffer_get_frame_id(buffer);
    const int bits = pixel_format == ARV_PIXEL_FORMAT_MONO_16 ? 16 : 8;
    // The fake checked that the buffer holds width * height pixels of this format before calling.
    auto* out = static_cast<std::uint8_t*>(const_cast<void*>(arv_buffer_get_data(buffer, nullptr)));
    if (out == nullptr || width <= 0 || height <= 0) return;
    if (pixel_format != ARV_PIXEL_FORMAT_MONO_8 && pixel_format != ARV_PIXEL_FORMAT_MONO_16) {
      std::fprintf(stderr, "panoptes_fake_gige: pixel format 0x%08x is not rendered; sending zeros\n",
                   pixel_format);
      std::memset(out, 0, static_cast<std::size_t>(width) * height);
      return;
    }
    // Positions depend only on the seed and the frame id, so a frame can be re-derived.
    std::mt19937_64 rng(options.seed * 1'000'003 + frame_id);
    const std::vector<testing::Spot> spots =
        testing::random_spot_grid(width, height, options.cell_px, options.sigma_min_px, options.sigma_max_px,
                                  rng, options.amplitude_dn);
    const panoptes::Image image = testing::render_spots(
        width, height, spots, options.background_dn, options.noise_dn, &rng, bits == 16 ? 256.0 : 1.0, bits);
    if (bits == 8) {
      std::memcpy(out, image.data.data(), image.data.size());
    } else {
      for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
          const std::uint16_t value = image.row16(y)[x];
          std::uint8_t* pixel = out + 2 * (static_cast<std::size_t>(y) * width + x);
          pixel[0] = static_cast<std::uint8_t>(value & 0xFF);  // GenICam: little-endian words
          pixel[1] = static_cast<std::uint8_t>(value >> 8);
        }
      }
    }
    if (truth == nullptr) return;
    // The fake stamps a frame before rendering it, so no frame can reach a client sooner than this
    // after its stamp: the latency floor a clock mapper will see.
    const std::int64_t ready_ns = g_get_real_time() * 1000;
    std::string line = "{\"frame\":" + std::to_string(frame_id) +
                       ",\"device_ns\":" + std::to_string(arv_buffer_get_timestamp(buffer)) +
                       ",\"ready_ns\":" + std::to_string(ready_ns) + ",\"width\":" + std::to_string(width) +
                       ",\"height\":" + std::to_string(height) + ",\"spots\":[";
    char number[64];
    for (std::size_t i = 0; i < spots.size(); ++i) {
      std::snprintf(number, sizeof(number), "%s[%.6f,%.6f]", i == 0 ? "" : ",", spots[i].x, spots[i].y);
      line += number;
    }
    line += "]}\n";
    std::lock_guard lock(mutex);
    std::fputs(line.c_str(), truth);
    std::fflush(truth);
  }
};

void fill_pattern(ArvBuffer* buffer, void* renderer, guint32 /*exposure_us*/, guint32 /*gain*/,
                  ArvPixelFormat pixel_format) {
  static_cast<Renderer*>(renderer)->fill(buffer, pixel_format);
}

// Parses the command line into `options`; returns the exit code to leave with, or nullopt to run.
std::optional<int> parse(int argc, char** argv, Options& options) {
  CLI::App app{
      "panoptes_fake_gige: a GigE Vision fake camera serving synthetic IR frames with known spots "
      "(run it only inside a network namespace whose only interface is lo)",
      "panoptes_fake_gige"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  app.add_option("--interface", options.interface_name, "network interface to listen on");
  app.add_option("--serial", options.serial, "serial number the camera announces");
  app.add_option("--truth", options.truth_file, "write every frame's spot positions to this JSONL file");
  app.add_option("--width", options.width, "image width, px")->check(CLI::Range(16, 4096));
  app.add_option("--height", options.height, "image height, px")->check(CLI::Range(16, 4096));
  app.add_option("--rate", options.frame_rate_hz, "frames per second")->check(CLI::Range(1.0, 1000.0));
  app.add_option("--loss", options.loss_ratio, "fraction of stream packets not sent, in [0, 1)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--cell", options.cell_px, "one spot per cell of this size, px")
      ->check(CLI::Range(16, 4096));
  app.add_option("--noise", options.noise_dn, "sensor noise sigma, DN");
  app.add_option("--seed", options.seed, "random seed");
  app.add_option("--duration", options.duration_s, "seconds to serve (0 = until SIGINT/SIGTERM)");
  return panoptes::parse_command_line(app, argc, argv, [&options] {
    if (options.loss_ratio >= 1) throw CLI::ValidationError("--loss", "must be in [0, 1)");
  });
}

int run(int argc, char** argv) {
  Renderer renderer;
  if (const auto exit_code = parse(argc, argv, renderer.options)) return *exit_code;
  const Options& options = renderer.options;
  if (!options.truth_file.empty()) {
    renderer.truth = std::fopen(options.truth_file.c_str(), "w");
    if (renderer.truth == nullptr) {
      std::fprintf(stderr, "panoptes_fake_gige: cannot write %s: %s\n", options.truth_file.c_str(),
                   std::strerror(errno));
      return 2;
    }
  }
  std::signal(SIGINT, request_stop);
  std::signal(SIGTERM, request_stop);

  auto* camera = static_cast<ArvGvFakeCamera*>(
      g_object_new(arv_gv_fake_camera_get_type(), "interface-name", options.interface_name.c_str(),
                   "serial-number", options.serial.c_str(), "gvsp-lost-ratio", options.loss_ratio, nullptr));
  if (camera == nullptr || !arv_gv_fake_camera_is_running(camera)) {
    std::fprintf(stderr, "panoptes_fake_gige: cannot listen on interface '%s'\n",
                 options.interface_name.c_str());
    if (camera != nullptr) g_object_unref(camera);
    return 1;
  }
  ArvFakeCamera* fake = arv_gv_fake_camera_get_fake_camera(camera);
  // The sensor is the image: a client asking for the full sensor gets width x height.
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_SENSOR_WIDTH, options.width);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_SENSOR_HEIGHT, options.height);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_WIDTH, options.width);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_HEIGHT, options.height);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_ACQUISITION_FRAME_PERIOD_US,
                                 static_cast<guint32>(1e6 / options.frame_rate_hz));
  arv_fake_camera_set_fill_pattern(fake, fill_pattern, &renderer);
  std::printf("panoptes_fake_gige: serving %dx%d at %g Hz on %s (packet loss %g)\n", options.width,
              options.height, options.frame_rate_hz, options.interface_name.c_str(), options.loss_ratio);
  std::fflush(stdout);

  const auto start = std::chrono::steady_clock::now();
  while (!g_stop.load()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (options.duration_s > 0 &&
        std::chrono::steady_clock::now() - start >= std::chrono::duration<double>(options.duration_s)) {
      break;
    }
  }
  g_object_unref(camera);  // stops and joins the camera's thread before the renderer goes away
  if (renderer.truth != nullptr) std::fclose(renderer.truth);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_fake_gige", [&] { return run(argc, argv); });
}
