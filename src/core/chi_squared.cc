#include "vi_ekf_slam/core/chi_squared.h"

#include <boost/math/distributions/chi_squared.hpp>
#include <stdexcept>

namespace vi_ekf_slam {

double chiSquaredCdf(double x, double dof) {
  if (!(dof > 0.0)) throw std::invalid_argument("chiSquaredCdf: dof must be > 0");
  if (!(x > 0.0)) return 0.0;
  return boost::math::cdf(boost::math::chi_squared_distribution<double>(dof), x);
}

double chiSquaredQuantile(double p, double dof) {
  if (!(p > 0.0 && p < 1.0)) throw std::invalid_argument("chiSquaredQuantile: p must be in (0,1)");
  if (!(dof > 0.0)) throw std::invalid_argument("chiSquaredQuantile: dof must be > 0");
  return boost::math::quantile(boost::math::chi_squared_distribution<double>(dof), p);
}

}  // namespace vi_ekf_slam
