// SPDX-License-Identifier: Apache-2.0
#include "panoptes/up_axis.h"

#include <cctype>
#include <cmath>

#include "panoptes/errors.h"

namespace panoptes {

UpAxis parse_up_axis(std::string_view text, const std::string& source) {
  if (text.size() == 1) {
    const int c = std::tolower(static_cast<unsigned char>(text[0]));
    if (c == 'z') return UpAxis::kZ;
    if (c == 'y') return UpAxis::kY;
  }
  throw ConfigError(source + "=" + std::string(text), "", "not an up axis (z or y)");
}

const char* up_axis_name(UpAxis axis) {
  return axis == UpAxis::kY ? "y" : "z";
}

std::array<double, 3> vector_to_up_axis(UpAxis axis, const std::array<double, 3>& v) {
  if (axis == UpAxis::kZ) return v;
  return {v[0], v[2], -v[1]};
}

std::array<double, 4> orientation_to_up_axis(UpAxis axis, const std::array<double, 4>& q) {
  if (axis == UpAxis::kZ) return q;
  // (cos 45°, -sin 45°, 0, 0) * q: the rotation of -90 degrees about x, then the body's rotation.
  const double h = std::sqrt(0.5);
  const double x = q[0];
  const double y = q[1];
  const double z = q[2];
  const double w = q[3];
  return {h * (x - w), h * (y + z), h * (z - y), h * (w + x)};
}

std::array<double, 6> covariance_to_up_axis(UpAxis axis, const std::array<double, 6>& c) {
  if (axis == UpAxis::kZ) return c;
  // c: xx xy xz yy yz zz; x' = x, y' = z, z' = -y.
  return {c[0], c[2], -c[1], c[5], -c[4], c[3]};
}

std::array<double, 3> sigmas_to_up_axis(UpAxis axis, const std::array<double, 3>& s) {
  if (axis == UpAxis::kZ) return s;
  return {s[0], s[2], s[1]};
}

}  // namespace panoptes
