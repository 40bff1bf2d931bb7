// SPDX-License-Identifier: Apache-2.0
// bench_detector: Detector::detect against OpenCV (threshold + findContours + moments, and
// threshold + connectedComponentsWithStats) and against a memcpy of the same frame, on the same
// frames in the same run, one thread. Also absolute times at seed 004 Table 2 frame sizes, for
// 8-bit and 16-bit (Mono12) input, and the prediction-guided search.
//   bench_detector [--json] [--min-time <s>] [--blobs <n>]
// With --json the last line of output is one JSON object (docs/benchmarks.md).
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "panoptes/camera/detector.h"
#include "panoptes/process.h"
#include "spot_renderer.h"

namespace {

using panoptes::Image;
using panoptes::camera::Detector;
using panoptes::camera::SearchWindow;
namespace testing = panoptes::camera::testing;

struct Frame {
  Image image;
  std::vector<testing::Spot> spots;
};

// `blobs` Gaussian spots (sigma 0.8-3 px, peaks 120-400 DN, some saturated) at random positions
// on a 10 DN background with 2 DN noise; 16-bit frames are the same picture times 16 (Mono12).
Frame make_frame(int width, int height, int blobs, int bits, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> x(20.0, width - 20.0), y(20.0, height - 20.0);
  std::uniform_real_distribution<double> sigma(0.8, 3.0), peak(120.0, 400.0);
  Frame frame;
  for (int i = 0; i < blobs; ++i) frame.spots.push_back({x(rng), y(rng), sigma(rng), peak(rng)});
  frame.image = testing::render_spots(width, height, frame.spots, 10, 2.0, &rng, bits > 8 ? 16.0 : 1.0, bits);
  return frame;
}

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Runs every case in turn for `rounds` rounds of about min_time/rounds each and reports the
// median per-call time over all calls: interleaving keeps a machine-wide slowdown from
// favouring one case.
struct Case {
  std::string name;
  std::function<std::size_t()> run;  // returns something derived from the result (kept alive)
  std::vector<double> samples;
  std::size_t result = 0;
};

void measure(std::vector<Case>& cases, double min_time, int rounds = 5) {
  for (Case& c : cases) c.result = c.run();  // warm-up: caches, scratch buffers
  for (int round = 0; round < rounds; ++round) {
    for (Case& c : cases) {
      const double until = now_s() + min_time / rounds;
      do {
        const double begin = now_s();
        c.result = c.run();
        c.samples.push_back(now_s() - begin);
      } while (now_s() < until);
    }
  }
}

double median_us(std::vector<double> samples) {
  if (samples.empty()) return 0;
  std::nth_element(samples.begin(), samples.begin() + static_cast<std::ptrdiff_t>(samples.size() / 2),
                   samples.end());
  return samples[samples.size() / 2] * 1e6;
}

cv::Mat view(const Image& image) {
  return cv::Mat(image.height, image.width, image.bits > 8 ? CV_16UC1 : CV_8UC1,
                 const_cast<std::uint8_t*>(image.data.data()));
}

std::size_t opencv_contours(const Image& image, cv::Mat& binary) {
  const cv::Mat input = view(image);
  cv::threshold(input, binary, 64, 255, cv::THRESH_BINARY);
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(binary, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  std::size_t found = 0;
  for (const auto& contour : contours) {
    // Intensity moments over each blob's bounding box: the nearest OpenCV equivalent of a
    // weighted centroid.
    const cv::Rect box = cv::boundingRect(contour);
    const cv::Moments m = cv::moments(input(box), false);
    if (m.m00 > 0) ++found;
  }
  return found;
}

std::size_t opencv_components(const Image& image, cv::Mat& binary, cv::Mat& labels, cv::Mat& stats,
                              cv::Mat& centroids) {
  cv::threshold(view(image), binary, 64, 255, cv::THRESH_BINARY);
  // Grana's algorithm was the fastest with statistics of the ones Debian's OpenCV 4.6 offers
  // (9.5 ms against 27-39 ms for the others on this frame), so the baseline is its best.
  return static_cast<std::size_t>(
             cv::connectedComponentsWithStats(binary, labels, stats, centroids, 8, CV_32S, cv::CCL_GRANA)) -
         1;
}

int usage(const char* message) {
  std::fprintf(stderr, "bench_detector: %s\nusage: bench_detector [--json] [--min-time <s>] [--blobs <n>]\n",
               message);
  return 2;
}

int run(int argc, char** argv) {
  bool json = false;
  double min_time = 1.0;
  int blob_count = 30;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--json") {
      json = true;
    } else if (arg == "--min-time" && i + 1 < argc) {
      min_time = std::atof(argv[++i]);
      if (!(min_time > 0)) return usage("--min-time must be > 0");
    } else if (arg == "--blobs" && i + 1 < argc) {
      blob_count = std::atoi(argv[++i]);
      if (blob_count < 1) return usage("--blobs must be >= 1");
    } else if (arg == "--help" || arg == "-h") {
      std::printf(
          "bench_detector: times the blob detector against OpenCV and memcpy on the same frames.\n"
          "  --json          print one JSON object on the last line\n"
          "  --min-time <s>  measuring time per comparison group (default 1)\n"
          "  --blobs <n>     blobs per frame (default 30)\n");
      return 0;
    } else {
      return usage(("unknown argument '" + arg + "'").c_str());
    }
  }
  cv::setNumThreads(1);

  // 1. The comparison on one 2048x2048 8-bit frame.
  const Frame big = make_frame(2048, 2048, blob_count, 8, 2048);
  Detector detector;
  Detector guided_detector;
  Detector masked_detector;  // a blind region switches the scan to the per-pixel threshold map
  masked_detector.add_mask(panoptes::camera::MaskRegion::rectangle(0, 0, 64, 64));
  std::vector<SearchWindow> windows;
  for (const auto& spot : big.spots) windows.push_back({spot.x + 0.7, spot.y - 0.4, 10, 10});
  cv::Mat binary, labels, stats, centroids;
  std::vector<std::uint8_t> copy(big.image.data.size());
  std::vector<Case> comparison = {
      {"panoptes", [&] { return detector.detect(big.image).size(); }, {}, 0},
      {"opencv_findcontours_moments", [&] { return opencv_contours(big.image, binary); }, {}, 0},
      {"opencv_connectedcomponents",
       [&] { return opencv_components(big.image, binary, labels, stats, centroids); },
       {},
       0},
      {"memcpy",
       [&] {
         std::memcpy(copy.data(), big.image.data.data(), copy.size());
         return static_cast<std::size_t>(copy[copy.size() / 2]);
       },
       {},
       0},
      {"panoptes_guided", [&] { return guided_detector.detect(big.image, windows).size(); }, {}, 0},
      {"panoptes_threshold_map", [&] { return masked_detector.detect(big.image).size(); }, {}, 0},
  };
  measure(comparison, min_time * static_cast<double>(comparison.size()));

  // 2. Absolute times at the frame sizes of seed 004 Table 2, 8-bit and 16-bit.
  struct Size {
    int width, height;
  };
  const Size sizes[] = {{640, 480}, {1280, 1024}, {2048, 1088}, {2048, 2048}};
  std::vector<Frame> frames;
  std::vector<Detector> detectors(8);
  std::vector<Case> by_size;
  for (const Size& size : sizes) {
    for (const int bits : {8, 12}) {
      frames.push_back(make_frame(size.width, size.height, blob_count, bits, 7));
    }
  }
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const Image& image = frames[i].image;
    by_size.push_back({std::to_string(image.width) + "x" + std::to_string(image.height) + "_" +
                           (image.bits > 8 ? "16bit" : "8bit"),
                       [&, i] { return detectors[i].detect(frames[i].image).size(); },
                       {},
                       0});
  }
  measure(by_size, min_time * 2);

  const double ours = median_us(comparison[0].samples);
  const double contours = median_us(comparison[1].samples);
  const double components = median_us(comparison[2].samples);
  const double memcpy_us = median_us(comparison[3].samples);
  const double guided = median_us(comparison[4].samples);
  const double with_map = median_us(comparison[5].samples);
  std::printf("2048x2048 8-bit, %d blobs, one thread (median per frame):\n", blob_count);
  for (const Case& c : comparison) {
    std::printf("  %-30s %9.1f us   (%zu calls, result %zu)\n", c.name.c_str(), median_us(c.samples),
                c.samples.size(), c.result);
  }
  std::printf(
      "  ratio vs findContours+moments  %.3f\n  ratio vs connectedComponents   %.3f\n"
      "  ratio vs memcpy                %.3f\n",
      ours / contours, ours / components, ours / memcpy_us);
  std::printf("by frame size:\n");
  for (const Case& c : by_size) {
    std::printf("  %-22s %9.1f us   (%zu blobs)\n", c.name.c_str(), median_us(c.samples), c.result);
  }
  if (json) {
    std::string sizes_json;
    for (const Case& c : by_size) {
      sizes_json += (sizes_json.empty() ? "" : ", ") + std::string("\"") + c.name +
                    "_us\": " + std::to_string(median_us(c.samples));
    }
    std::printf(
        "{\"frame\": \"2048x2048_8bit\", \"blobs\": %d, \"detected\": %zu, \"panoptes_us\": %.2f, "
        "\"opencv_findcontours_moments_us\": %.2f, \"opencv_connectedcomponents_us\": %.2f, \"memcpy_us\": "
        "%.2f, "
        "\"panoptes_guided_us\": %.2f, \"panoptes_threshold_map_us\": %.2f, \"ratio_vs_findcontours\": %.4f, "
        "\"ratio_vs_connectedcomponents\": %.4f, "
        "\"ratio_vs_memcpy\": %.4f, \"sizes\": {%s}}\n",
        blob_count, comparison[0].result, ours, contours, components, memcpy_us, guided, with_map,
        ours / contours, ours / components, ours / memcpy_us, sizes_json.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("bench_detector", [&] { return run(argc, argv); });
}
