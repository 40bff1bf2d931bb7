// SPDX-License-Identifier: Apache-2.0
// estimator_node's command line (architecture.md, Contracts): modes, files, and the settings that
// may also come from --config <yaml>. Precedence: defaults < --config file < explicit flags.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "panoptes/dds/security.h"
#include "panoptes/session/estimator_config.h"

namespace panoptes::estimator_app {

struct NodeCommandLine {
  std::string calibration_file;
  std::string bodies_file;
  std::string landmarks_file;  // inside-out mode (docs/inside_out.md)
  std::string config_file;
  bool print_config = false;
  std::vector<std::string> in_features;
  std::string in_recording;  // offline from an MCAP recording (implies no DDS)
  bool no_dds = false;
  std::string out_tracks;
  std::string out_poses;
  std::string out_chains;  // Chain JSONL (docs/articulated.md)
  // Live auto-labelling's labels JSONL (the subject models are settings: EstimatorConfig::subjects).
  std::string out_labels;
  std::string dds_profile;
  dds::SecurityOptions security;
  bool shared_memory = false;  // --shared-memory (docs/protocol.md, "A peer that dies")
  bool replay_arrival = false;
  double duration_s = 0.0;
  bool latency_probe = false;
  bool quiet = false;
  std::string surface_file;  // surface mode (docs/surface.md): a YAML with a `surface:` section
  std::string out_strokes;   // surface mode: Stroke JSONL
  // The settings flags given explicitly, applied over the --config file.
  std::vector<std::function<void(session::EstimatorConfig&)>> overrides;

  // Defaults, then the --config file, then the explicit flags. Throws ConfigError.
  session::EstimatorConfig effective_config() const;
};

// Parses argv (--help prints the defaults). Returns the exit code to leave with, or nullopt.
std::optional<int> parse_node_command_line(int argc, char** argv, NodeCommandLine& command_line);

}  // namespace panoptes::estimator_app
