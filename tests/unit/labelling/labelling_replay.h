// SPDX-License-Identifier: Apache-2.0
// A labelled trial played as anonymous tracks for the labelling tests: the markers with shuffled
// 64-bit track ids, 0.5 mm noise, occlusion gaps after which a marker comes back under a new id,
// false points near the body (test_labeller.cpp, test_offline_labelling.cpp).
#pragma once

#include <algorithm>
#include <cstdint>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/labelling/labeller.h"
#include "panoptes/labelling/subject_model.h"

namespace panoptes::labelling {

struct Replay {
  std::mt19937_64 rng;
  double gap_probability = 0.004;  // per visible marker-frame
  double ghosts_per_frame = 0.3;
};

// One frame's points: the walk's markers (ids change after a gap), ghosts near the body.
struct Stream {
  std::vector<std::uint64_t> id;  // per marker, 0 while hidden
  std::vector<int> hidden_for;
  struct Ghost {
    std::uint64_t id;
    Eigen::Vector3d at;
    int frames;
  };
  std::vector<Ghost> ghosts;
};

inline std::vector<TrackPoint> next_frame(const MarkerSamples& walk, std::size_t f, Replay& replay,
                                          Stream& stream, std::map<std::uint64_t, std::string>& truth) {
  std::normal_distribution<double> noise(0.0, 0.0005);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<TrackPoint> points;
  for (std::size_t m = 0; m < walk.point_count(); ++m) {
    if (stream.hidden_for[m] > 0) --stream.hidden_for[m];
    if (!walk.is_valid(f, m) || stream.hidden_for[m] > 0) {
      stream.id[m] = 0;
      continue;
    }
    if (stream.id[m] != 0 && unit(replay.rng) < replay.gap_probability) {
      stream.id[m] = 0;
      stream.hidden_for[m] = 5 + static_cast<int>(unit(replay.rng) * 20);
      continue;
    }
    if (stream.id[m] == 0) stream.id[m] = replay.rng();
    truth[stream.id[m]] = walk.names[m];
    const Eigen::Vector3d n(noise(replay.rng), noise(replay.rng), noise(replay.rng));
    points.push_back({stream.id[m], walk.position(f, m) + n});
  }
  std::poisson_distribution<int> births(replay.ghosts_per_frame);
  for (int g = births(replay.rng); g > 0 && !points.empty(); --g) {
    const auto& near = points[static_cast<std::size_t>(unit(replay.rng) * points.size())].position_m;
    const Eigen::Vector3d direction =
        Eigen::Vector3d(noise(replay.rng), noise(replay.rng), noise(replay.rng)).normalized();
    stream.ghosts.push_back({replay.rng(), near + direction * (0.03 + 0.22 * unit(replay.rng)),
                             1 + static_cast<int>(unit(replay.rng) * 6)});
  }
  for (auto& ghost : stream.ghosts) {
    if (ghost.frames-- > 0) points.push_back({ghost.id, ghost.at});
  }
  std::shuffle(points.begin(), points.end(), replay.rng);
  return points;
}

}  // namespace panoptes::labelling
