// Chi-square distribution functions for gating (2 dof per observation) and NEES bands (6*M dof),
// from boost::math (header-only, within the core's dependency rule).
#pragma once

namespace vi_ekf_slam {

/// P(X <= x) for X ~ chi^2(dof).
double chiSquaredCdf(double x, double dof);
/// x such that P(X <= x) = p, for 0 < p < 1.
double chiSquaredQuantile(double p, double dof);

}  // namespace vi_ekf_slam
