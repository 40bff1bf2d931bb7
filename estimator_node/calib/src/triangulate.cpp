// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calib/triangulate.h"

#include "panoptes/triangulation.h"

namespace panoptes::calib {

std::optional<Eigen::Vector3d> triangulate(const std::vector<CameraModel>& models,
                                           const std::vector<Eigen::Vector2d>& pixels) {
  if (models.size() != pixels.size()) return std::nullopt;
  std::vector<PixelObservation> observations;
  observations.reserve(models.size());
  for (std::size_t i = 0; i < models.size(); ++i) observations.push_back({&models[i], pixels[i]});
  const auto triangulated = panoptes::triangulate(observations);
  if (!triangulated) return std::nullopt;
  return triangulated->point;
}

}  // namespace panoptes::calib
