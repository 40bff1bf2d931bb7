// SPDX-License-Identifier: Apache-2.0
// Cubic Hermite interpolation: the one place for it (the wand track's Catmull-Rom segments in
// calibration, the spline gap fill of offline labelling).
#pragma once

namespace panoptes {

// Cubic Hermite interpolation on a segment that starts at t0_s and lasts h_s, from value p0 with
// tangent m0 (per second) to p1 with tangent m1, at time dt_s; T is double or a Ceres Jet.
template <class T>
T cubic_hermite(double t0_s, double h_s, double p0, double m0, double p1, double m1, const T& dt_s) {
  const T tau = (dt_s - T(t0_s)) / T(h_s);
  const T tau2 = tau * tau, tau3 = tau2 * tau;
  const T h00 = T(2.0) * tau3 - T(3.0) * tau2 + T(1.0);
  const T h10 = tau3 - T(2.0) * tau2 + tau;
  const T h01 = T(-2.0) * tau3 + T(3.0) * tau2;
  const T h11 = tau3 - tau2;
  const T h(h_s);
  return h00 * T(p0) + h10 * h * T(m0) + h01 * T(p1) + h11 * h * T(m1);
}

}  // namespace panoptes
