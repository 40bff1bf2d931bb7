// SPDX-License-Identifier: Apache-2.0
// Bodies made in the console's 3D view (docs/console.md, "Bodies from markers"; issue 34 item 3):
// the page's checked request (name, track ids, pivot) runs `panoptes_ctl body create` as a child
// process, which averages the tracks over 30 frames on the bus, makes and validates the body as
// the CLI does and appends it to the bodies file a running estimator reloads. One place for that
// maths (tools/ctl); the console only runs it and hands the outcome to the page that asked.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "panoptes/console/command_gate.h"
#include "panoptes/console/console_state.h"

namespace panoptes::console {

struct BodyMakerOptions {
  std::filesystem::path ctl;          // the panoptes_ctl program
  std::filesystem::path bodies_file;  // appended to; empty: the page cannot make bodies
  std::filesystem::path work_dir;     // the child's log
  std::string dds_profile;            // passed to the child ("" : its default)
  int frames = 30;                    // positions averaged per track
  double timeout_s = 5;               // for the tracks' frames
};

class BodyMaker {
 public:
  BodyMaker(BodyMakerOptions options, ConsoleState& state);
  ~BodyMaker();  // a running child is stopped
  BodyMaker(const BodyMaker&) = delete;
  BodyMaker& operator=(const BodyMaker&) = delete;

  // Starts making the body for browser `client`; "" when started, else why not (no bodies file,
  // another body being made). Thread-safe.
  std::string handle(const BodyCreateRequest& request, std::uint64_t client);
  // Reaps a finished child: its outcome (applied with the body's JSON line, or rejected with the
  // CLI's error) goes to the asking browser through the state. Call a few times a second.
  void poll();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace panoptes::console
