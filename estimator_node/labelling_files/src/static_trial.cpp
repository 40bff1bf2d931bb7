// SPDX-License-Identifier: Apache-2.0
#include "panoptes/labelling_files/static_trial.h"

#include <algorithm>
#include <cctype>
#include <string>

#include "panoptes/formats/c3d.h"
#include "panoptes/formats/trc.h"

namespace panoptes::labelling {

MarkerSamples load_marker_samples(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  MarkerTrajectories data = extension == ".c3d" ? load_c3d(path) : load_trc(path);
  MarkerSamples samples;
  samples.source = path.string();
  samples.rate_hz = data.data_rate_hz;
  samples.names = std::move(data.marker_names);
  samples.positions = std::move(data.positions);
  samples.valid = std::move(data.valid);
  return samples;
}

}  // namespace panoptes::labelling
