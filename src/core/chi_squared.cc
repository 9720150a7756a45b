#include "vi_ekf_slam/core/chi_squared.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace vi_ekf_slam {

namespace {
/// Regularized lower incomplete gamma P(a, x).
double regularizedGammaP(double a, double x) {
  if (x <= 0.0) return 0.0;
  const double log_prefix = -x + a * std::log(x) - std::lgamma(a);
  if (x < a + 1.0) {  // series
    double ap = a, sum = 1.0 / a, del = sum;
    for (int n = 0; n < 10000; ++n) {
      ap += 1.0;
      del *= x / ap;
      sum += del;
      if (std::abs(del) < std::abs(sum) * 1e-15) break;
    }
    return sum * std::exp(log_prefix);
  }
  // Continued fraction for Q(a, x) (modified Lentz).
  const double tiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
  for (int i = 1; i < 10000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double del = d * c;
    h *= del;
    if (std::abs(del - 1.0) < 1e-15) break;
  }
  return 1.0 - std::exp(log_prefix) * h;
}
}  // namespace

double chiSquaredCdf(double x, double dof) {
  if (!(dof > 0.0)) throw std::invalid_argument("chiSquaredCdf: dof must be > 0");
  return regularizedGammaP(0.5 * dof, 0.5 * x);
}

double chiSquaredQuantile(double p, double dof) {
  if (!(p > 0.0 && p < 1.0)) throw std::invalid_argument("chiSquaredQuantile: p must be in (0,1)");
  double lo = 0.0, hi = dof + 20.0 * std::sqrt(2.0 * dof) + 60.0;
  while (chiSquaredCdf(hi, dof) < p) hi *= 2.0;
  for (int i = 0; i < 200 && hi - lo > 1e-12 * std::max(1.0, hi); ++i) {
    const double mid = 0.5 * (lo + hi);
    (chiSquaredCdf(mid, dof) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace vi_ekf_slam
