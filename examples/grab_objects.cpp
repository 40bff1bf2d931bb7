// SPDX-License-Identifier: Apache-2.0
// grab_objects: the seed's chess application in miniature (seed 000 §6.4.5; docs/articulated.md,
// "Live"). It reads articulated chains through the client library, keeps a few virtual objects at
// fixed places, and when a finger makes a grab gesture it picks up the nearest free object within
// --radius of the fingertip, carries it with the tip, and puts it down where the release happens.
// It prints what it does and, with --out, writes every action as JSON Lines.
//   grab_objects [--object NAME=X,Y,Z]... [--radius M] [--chain NAME] [--out FILE.jsonl]
//                [--duration S] [--idle-exit S] [--domain N] [--profile FILE]
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>

#include "panoptes/client/client.h"

namespace {

namespace client = panoptes::client;
using client::Vec3;

struct VirtualObject {
  std::string name;
  Vec3 position{};
  Vec3 start{};            // where it was before its current grab
  std::string held_by;     // chain name; "" when lying still
  Vec3 offset_from_tip{};  // kept while held: the object moves rigidly with the tip
};

struct Arguments {
  std::vector<VirtualObject> objects;
  double radius_m = 0.03;
  std::string chain;
  std::string out;
  double duration_s = 0.0;
  double idle_exit_s = 3.0;
  client::ClientOptions options;
};

double distance(const Vec3& a, const Vec3& b) {
  return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}

// Objects, grabs and releases; fed by the client's chain callback (one thread at a time).
class Table {
 public:
  Table(std::vector<VirtualObject> objects, double radius_m, std::string only_chain, std::FILE* out)
      : objects_(std::move(objects)), radius_m_(radius_m), only_chain_(std::move(only_chain)), out_(out) {}

  void on_update(const client::ChainUpdate& update) {
    std::lock_guard lock(mutex_);
    ++updates_;
    if (update.receive_ns > 0 && update.stamp_ns > 0)
      latencies_ns_.push_back(update.receive_ns - update.stamp_ns);
    // Events first: a release in this update puts the object down at the event's tip.
    for (const auto& event : update.events) {
      if (!only_chain_.empty() && event.chain != only_chain_) continue;
      if (event.kind == client::GrabKind::kGrab)
        grab(event);
      else
        release(event);
    }
    for (auto& object : objects_) {
      if (object.held_by.empty()) continue;
      const client::Chain* chain = update.chain(object.held_by);
      if (chain == nullptr || !chain->tracking()) continue;  // not seen: it stays where it was
      for (int i = 0; i < 3; ++i) object.position[i] = chain->tip[i] + object.offset_from_tip[i];
    }
  }

  // "N updates, G grabs (M missed: nothing within reach), R releases; latency ..." and the objects.
  void print_summary() const {
    std::lock_guard lock(mutex_);
    std::printf("grab_objects: %llu chain updates, %d grabs (%d with nothing in reach), %d releases\n",
                static_cast<unsigned long long>(updates_), grabs_, empty_grabs_, releases_);
    print_latency("chain updates (rt/panoptes/chains)", latencies_ns_);
    print_latency("frames of the same run (rt/panoptes/frames)", frame_latencies_ns_);
    for (const auto& object : objects_)
      std::printf("grab_objects: %s at [%.3f, %.3f, %.3f]%s\n", object.name.c_str(), object.position[0],
                  object.position[1], object.position[2],
                  object.held_by.empty() ? "" : (" held by " + object.held_by).c_str());
  }

  // The same latency for the MocapFrames this client receives anyway: the reference beside it.
  void on_frame(const client::Frame& frame) {
    std::lock_guard lock(mutex_);
    if (frame.receive_ns > 0 && frame.stamp_ns > 0)
      frame_latencies_ns_.push_back(frame.receive_ns - frame.stamp_ns);
  }

  std::uint64_t updates() const {
    std::lock_guard lock(mutex_);
    return updates_;
  }

 private:
  static void print_latency(const char* what, std::vector<std::int64_t> latencies_ns) {
    if (latencies_ns.empty()) return;
    std::sort(latencies_ns.begin(), latencies_ns.end());
    const auto at = [&](double q) {
      return static_cast<double>(
          latencies_ns[static_cast<std::size_t>(q * static_cast<double>(latencies_ns.size() - 1))]);
    };
    std::printf("grab_objects: latency stamp -> client of %s: p50 %.3f ms, p95 %.3f ms, max %.3f ms (%zu)\n",
                what, at(0.5) * 1e-6, at(0.95) * 1e-6, at(1.0) * 1e-6, latencies_ns.size());
  }

  void grab(const client::GrabEvent& event) {
    ++grabs_;
    VirtualObject* nearest = nullptr;
    for (auto& object : objects_) {
      if (!object.held_by.empty() || distance(object.position, event.tip) > radius_m_) continue;
      if (nearest == nullptr || distance(object.position, event.tip) < distance(nearest->position, event.tip))
        nearest = &object;
    }
    if (nearest == nullptr) {
      ++empty_grabs_;
      std::printf("%s grabs at [%.3f, %.3f, %.3f]: nothing within %.0f mm\n", event.chain.c_str(),
                  event.tip[0], event.tip[1], event.tip[2], radius_m_ * 1e3);
      write("grab_nothing", event, nullptr, 0.0);
      return;
    }
    nearest->held_by = event.chain;
    nearest->start = nearest->position;
    for (int i = 0; i < 3; ++i) nearest->offset_from_tip[i] = nearest->position[i] - event.tip[i];
    std::printf("%s grabs %s at [%.3f, %.3f, %.3f] (%.1f mm from the tip)\n", event.chain.c_str(),
                nearest->name.c_str(), nearest->position[0], nearest->position[1], nearest->position[2],
                distance(nearest->position, event.tip) * 1e3);
    write("grab", event, nearest, 0.0);
  }

  void release(const client::GrabEvent& event) {
    ++releases_;
    const bool holding = std::any_of(objects_.begin(), objects_.end(), [&](const VirtualObject& object) {
      return object.held_by == event.chain;
    });
    if (!holding) {
      std::printf("%s releases at [%.3f, %.3f, %.3f]: it held nothing\n", event.chain.c_str(), event.tip[0],
                  event.tip[1], event.tip[2]);
      write("release_nothing", event, nullptr, 0.0);
    }
    for (auto& object : objects_) {
      if (object.held_by != event.chain) continue;
      for (int i = 0; i < 3; ++i) object.position[i] = event.tip[i] + object.offset_from_tip[i];
      object.held_by.clear();
      const double moved_m = distance(object.position, object.start);
      std::printf("%s releases %s at [%.3f, %.3f, %.3f], moved %.1f mm\n", event.chain.c_str(),
                  object.name.c_str(), object.position[0], object.position[1], object.position[2],
                  moved_m * 1e3);
      write("release", event, &object, moved_m);
    }
  }

  void write(const char* action, const client::GrabEvent& event, const VirtualObject* object,
             double moved_m) {
    std::fflush(stdout);
    if (out_ == nullptr) return;
    std::fprintf(out_,
                 "{\"action\": \"%s\", \"chain\": \"%s\", \"stamp_ns\": %lld, \"tip\": [%.6f, %.6f, %.6f], "
                 "\"bend\": %.4f, \"object\": \"%s\", \"position\": [%.6f, %.6f, %.6f], \"moved_m\": %.6f}\n",
                 action, event.chain.c_str(), static_cast<long long>(event.stamp_ns), event.tip[0],
                 event.tip[1], event.tip[2], event.bend, object ? object->name.c_str() : "",
                 object ? object->position[0] : 0.0, object ? object->position[1] : 0.0,
                 object ? object->position[2] : 0.0, moved_m);
    std::fflush(out_);
  }

  mutable std::mutex mutex_;
  std::vector<VirtualObject> objects_;
  double radius_m_;
  std::string only_chain_;
  std::FILE* out_;
  std::uint64_t updates_ = 0;
  int grabs_ = 0;
  int empty_grabs_ = 0;
  int releases_ = 0;
  std::vector<std::int64_t> latencies_ns_;
  std::vector<std::int64_t> frame_latencies_ns_;
};

// "NAME=X,Y,Z" as an object; nullopt when it is not one.
std::optional<VirtualObject> parse_object(const std::string& text) {
  const auto equals = text.find('=');
  if (equals == 0 || equals == std::string::npos) return std::nullopt;
  VirtualObject object;
  object.name = text.substr(0, equals);
  const char* cursor = text.c_str() + equals + 1;
  for (int i = 0; i < 3; ++i) {
    char* end = nullptr;
    object.position[i] = std::strtod(cursor, &end);
    if (end == cursor || !std::isfinite(object.position[i]) || *end != (i < 2 ? ',' : '\0'))
      return std::nullopt;
    cursor = end + 1;
  }
  object.start = object.position;
  return object;
}

// Returns the exit code to leave with, or -1 to go on.
int parse(int argc, char** argv, Arguments& args) {
  CLI::App app{"grab_objects: pick up virtual objects with a finger's grab gestures (docs/articulated.md)"};
  app.option_defaults()->always_capture_default();
  std::vector<std::string> objects;
  app.add_option("--object", objects,
                 "NAME=X,Y,Z: a virtual object at a world position, m; repeatable (default: three around "
                 "the finger of deploy/scenes/hand.yaml)");
  app.add_option("--radius", args.radius_m, "A grab picks the nearest free object within this of the tip, m")
      ->check(CLI::Range(1e-4, 10.0));
  app.add_option("--chain", args.chain, "Only this chain grabs (default: every chain)");
  app.add_option("--out", args.out, "Every grab and release as JSON Lines");
  app.add_option("--duration", args.duration_s, "Stop after this many seconds (0: until --idle-exit)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--idle-exit", args.idle_exit_s,
                 "Stop when no chain update came for this long after the first, s")
      ->check(CLI::PositiveNumber);
  app.add_option("--domain", args.options.domain_id, "DDS domain, 0..232 (default: $PANOPTES_DOMAIN, else 0)")
      ->check(CLI::Range(0, 232));  // a negative id does not mean "the environment": that is leaving it out
  app.add_option("--profile", args.options.profile_file,
                 "DDS XML profile (default: the installed loopback.xml)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error) == 0 ? 0 : 2;  // --help, or a usage error (CLI11's own codes are 100 and up)
  }
  if (objects.empty()) objects = {"pawn=0.08,0.00,0.96", "rook=0.06,0.04,0.95", "knight=0.06,-0.04,0.95"};
  for (const auto& text : objects) {
    auto object = parse_object(text);
    if (!object) {
      std::fprintf(stderr, "grab_objects: --object %s: not NAME=X,Y,Z\n", text.c_str());
      return 2;
    }
    args.objects.push_back(*object);
  }
  return -1;
}

}  // namespace

int main(int argc, char** argv) {
  try {  // the parser's set-up may throw too (out of memory)
    Arguments args;
    if (const int code = parse(argc, argv, args); code >= 0) return code;
    std::FILE* out = args.out.empty() ? nullptr : std::fopen(args.out.c_str(), "w");
    if (!args.out.empty() && out == nullptr) {
      std::fprintf(stderr, "grab_objects: --out %s: cannot write\n", args.out.c_str());
      return 2;
    }
    Table table(args.objects, args.radius_m, args.chain, out);
    client::Client chain_client(args.options);
    std::atomic<std::int64_t> last_update_ns{0};
    chain_client.add_callback([&](const client::Frame& frame) { table.on_frame(frame); });
    chain_client.add_chain_callback([&](const client::ChainUpdate& update) {
      table.on_update(update);
      last_update_ns = std::chrono::steady_clock::now().time_since_epoch().count();
    });
    const auto start = std::chrono::steady_clock::now();
    const auto seconds_since = [](std::chrono::steady_clock::time_point then) {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - then).count();
    };
    while (args.duration_s <= 0 || seconds_since(start) < args.duration_s) {
      const std::int64_t last = last_update_ns;
      if (last != 0 && seconds_since(std::chrono::steady_clock::time_point(
                           std::chrono::steady_clock::duration(last))) >= args.idle_exit_s)
        break;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    chain_client.close();
    table.print_summary();
    const auto stats = chain_client.stats();
    std::printf("grab_objects: %llu grab/release events received, %llu malformed updates\n",
                static_cast<unsigned long long>(stats.grab_events_received),
                static_cast<unsigned long long>(stats.chain_updates_malformed));
    if (out != nullptr) std::fclose(out);
    return table.updates() > 0 ? 0 : 1;
  } catch (const client::OptionError& error) {  // e.g. $PANOPTES_DOMAIN=abc: a usage error
    std::fprintf(stderr, "grab_objects: %s\n", error.what());
    return 2;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "grab_objects: %s\n", error.what());
    return 1;
  }
}
