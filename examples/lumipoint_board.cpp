// SPDX-License-Identifier: Apache-2.0
// lumipoint_board: the LumiPoint drawing board (seed 003 §2.3.2; docs/clients.md, "Strokes"). It
// reads stroke events from estimator_node's surface mode through the client library and draws
// each stroke in its own colour on a white board the shape of the wall; headless, it writes the
// board as a PPM image (and, with --events, every event received as JSON Lines).
//   lumipoint_board --out board.ppm [--events events.jsonl] [--width PX] [--duration S]
//                   [--idle-exit S] [--domain N] [--profile FILE]
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "panoptes/client/client.h"

namespace {

namespace client = panoptes::client;

const char* const kUsage =
    "usage: lumipoint_board --out FILE.ppm [--events FILE.jsonl] [--width PX] [--duration S] [--idle-exit "
    "S]\n"
    "                       [--domain N] [--profile FILE]\n"
    "  --out FILE      the board as a binary PPM image, written at the end\n"
    "  --events FILE   every stroke event received, as JSON Lines\n"
    "  --width PX      image width; the height follows the wall's aspect ratio (default 900)\n"
    "  --duration S    stop after S seconds (default 0: until --idle-exit)\n"
    "  --idle-exit S   stop when no event has arrived for S s after the first (default 3)\n"
    "  --domain N      DDS domain, 0..232 (default: $PANOPTES_DOMAIN, else 0)\n"
    "  --profile FILE  DDS XML profile (default: the installed loopback.xml)\n";

struct Arguments {
  std::string out;
  std::string events;
  int width = 900;
  double duration_s = 0.0;
  double idle_exit_s = 3.0;
  client::ClientOptions options;
};

using Rgb = std::array<unsigned char, 3>;

// Well separated, saturated colours: hue steps of the golden angle, by stroke id.
Rgb stroke_colour(std::uint32_t id) {
  const double hue = std::fmod(static_cast<double>(id) * 137.50776, 360.0) / 60.0;
  const double x = 1.0 - std::abs(std::fmod(hue, 2.0) - 1.0);
  std::array<double, 3> rgb{};
  switch (static_cast<int>(hue)) {
    case 0:
      rgb = {1, x, 0};
      break;
    case 1:
      rgb = {x, 1, 0};
      break;
    case 2:
      rgb = {0, 1, x};
      break;
    case 3:
      rgb = {0, x, 1};
      break;
    case 4:
      rgb = {x, 0, 1};
      break;
    default:
      rgb = {1, 0, x};
      break;
  }
  return {static_cast<unsigned char>(215 * rgb[0]), static_cast<unsigned char>(215 * rgb[1]),
          static_cast<unsigned char>(215 * rgb[2])};
}

class Board {
 public:
  void add(const client::Stroke& stroke) {
    if (stroke.surface_size[0] > 0 && stroke.surface_size[1] > 0) size_ = stroke.surface_size;
    strokes_[stroke.id].push_back(stroke.position);
  }

  // White board, strokes as 3 px wide polylines; the wall's t axis points up.
  bool write_ppm(const std::string& path, int width) const {
    const int height = std::max(1, static_cast<int>(std::lround(width * size_[1] / size_[0])));
    std::vector<unsigned char> pixels(static_cast<std::size_t>(width * height * 3), 255);
    const double scale = width / size_[0];
    auto plot = [&](double s, double t, const Rgb& colour) {
      const int cx = static_cast<int>(std::lround(s * scale)),
                cy = static_cast<int>(std::lround((size_[1] - t) * scale));
      for (int y = cy - 1; y <= cy + 1; ++y)
        for (int x = cx - 1; x <= cx + 1; ++x) {
          if (x < 0 || y < 0 || x >= width || y >= height) continue;
          std::copy(colour.begin(), colour.end(),
                    pixels.begin() + (static_cast<std::ptrdiff_t>(y) * width + x) * 3);
        }
    };
    for (const auto& [id, points] : strokes_) {
      const Rgb colour = stroke_colour(id);
      for (std::size_t i = 0; i < points.size(); ++i) {
        const auto& a = points[i];
        const auto& b = points[i + 1 < points.size() ? i + 1 : i];
        const int steps = 1 + static_cast<int>(std::hypot(b[0] - a[0], b[1] - a[1]) * scale);
        for (int k = 0; k <= steps; ++k) {
          const double f = static_cast<double>(k) / steps;
          plot(a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), colour);
        }
      }
    }
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << "P6\n" << width << ' ' << height << "\n255\n";
    out.write(reinterpret_cast<const char*>(pixels.data()), static_cast<std::streamsize>(pixels.size()));
    return static_cast<bool>(out);
  }

  std::size_t strokes() const { return strokes_.size(); }

 private:
  std::array<double, 2> size_{3.0, 1.0};
  std::map<std::uint32_t, std::vector<std::array<double, 2>>> strokes_;
};

const char* phase_name(client::StrokePhase phase) {
  return phase == client::StrokePhase::kBegin ? "begin"
         : phase == client::StrokePhase::kEnd ? "end"
                                              : "continue";
}

int usage_error(const std::string& reason) {
  std::fprintf(stderr, "lumipoint_board: %s\n%s", reason.c_str(), kUsage);
  return 2;
}

// --domain's value: a DDS domain id, 0..232 (the ids whose ports fit Fast DDS's port mapping);
// -1 for anything else (a sign, spaces, a fraction, a larger number).
int domain_id_of(const std::string& text) {
  if (text.empty() || text.size() > 3 || text.find_first_not_of("0123456789") != std::string::npos) return -1;
  const int id = std::stoi(text);
  return id <= 232 ? id : -1;
}

// Returns the exit code to leave with, or -1 to go on.
int parse(int argc, char** argv, Arguments& args) {
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") return std::printf("%s", kUsage), 0;
    if (i + 1 >= argc) return usage_error(arg + " needs a value");
    const std::string value = argv[++i];
    char* end = nullptr;
    const double number = std::strtod(value.c_str(), &end);
    const bool numeric = end != value.c_str() && *end == '\0' && std::isfinite(number) && number >= 0;
    if (arg == "--out") {
      args.out = value;
    } else if (arg == "--events") {
      args.events = value;
    } else if (arg == "--profile") {
      args.options.profile_file = value;
    } else if (arg == "--domain") {
      args.options.domain_id = domain_id_of(value);
      if (args.options.domain_id < 0)
        return usage_error("--domain " + value + ": not a DDS domain id (an integer 0..232)");
    } else if (!numeric) {
      return usage_error(arg.append(" ").append(value).append(": not a number >= 0"));
    } else if (arg == "--width" && number >= 16 && number <= 8192) {
      args.width = static_cast<int>(number);
    } else if (arg == "--duration") {
      args.duration_s = number;
    } else if (arg == "--idle-exit" && number > 0) {
      args.idle_exit_s = number;
    } else {
      return usage_error(
          std::string("unknown or out-of-range argument ").append(arg).append(" ").append(value));
    }
  }
  if (args.out.empty()) return usage_error("--out is required");
  return -1;
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  if (const int code = parse(argc, argv, args); code >= 0) return code;
  try {
    client::Client board_client(args.options);
    std::FILE* events = args.events.empty() ? nullptr : std::fopen(args.events.c_str(), "w");
    if (!args.events.empty() && events == nullptr) return usage_error("cannot write " + args.events);
    Board board;
    const auto start = std::chrono::steady_clock::now();
    auto last_event = start;
    bool any = false;
    const auto seconds_since = [](auto then) {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - then).count();
    };
    while ((args.duration_s <= 0 || seconds_since(start) < args.duration_s) &&
           (!any || seconds_since(last_event) < args.idle_exit_s)) {
      const auto result = board_client.wait_for_stroke(std::chrono::milliseconds(100));
      if (result.status != client::Status::kOk) continue;
      const client::Stroke& s = result.stroke;
      any = true;
      last_event = std::chrono::steady_clock::now();
      board.add(s);
      if (events != nullptr)
        std::fprintf(
            events,
            "{\"phase\": \"%s\", \"id\": %u, \"stamp_ns\": %lld, \"p\": [%.6f, %.6f], \"v\": [%.4f, %.4f], "
            "\"cameras\": %d, \"publish_ns\": %lld, \"receive_ns\": %lld}\n",
            phase_name(s.phase), s.id, static_cast<long long>(s.stamp_ns), s.position[0], s.position[1],
            s.velocity[0], s.velocity[1], s.cameras, static_cast<long long>(s.publish_ns),
            static_cast<long long>(s.receive_ns));
    }
    if (events != nullptr) std::fclose(events);
    if (!board.write_ppm(args.out, args.width)) {
      std::fprintf(stderr, "lumipoint_board: cannot write %s\n", args.out.c_str());
      return 1;
    }
    const auto stats = board_client.stats();
    std::fprintf(stderr, "lumipoint_board: %zu strokes, %llu events (%llu malformed) -> %s\n",
                 board.strokes(), static_cast<unsigned long long>(stats.strokes_received),
                 static_cast<unsigned long long>(stats.strokes_malformed), args.out.c_str());
    return any ? 0 : 1;
  } catch (const client::OptionError& error) {  // e.g. $PANOPTES_DOMAIN=abc: a usage error
    std::fprintf(stderr, "lumipoint_board: %s\n", error.what());
    return 2;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "lumipoint_board: %s\n", error.what());
    return 1;
  }
}
