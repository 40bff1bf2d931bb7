// SPDX-License-Identifier: Apache-2.0
// Records the console tests share.
#pragma once

#include "panoptes/console/console_records.h"

namespace panoptes::console::test {

// A 640x480 camera at 100 Hz.
inline CameraInfoRecord vga_info() {
  CameraInfoRecord info;
  info.nominal_rate_hz = 100;
  info.geometry.width = 640;
  info.geometry.height = 480;
  return info;
}

}  // namespace panoptes::console::test
