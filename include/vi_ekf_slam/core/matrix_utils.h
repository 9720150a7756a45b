// Small dense-matrix helpers that keep covariances well-formed.
#pragma once

#include <Eigen/Core>

namespace vi_ekf_slam {

/// P <- (P + P^T) / 2 in place (no aliasing temporaries).
inline void symmetrize(Eigen::MatrixXd& P) {
  const Eigen::Index n = P.rows();
  for (Eigen::Index j = 0; j < n; ++j) {
    for (Eigen::Index i = j + 1; i < n; ++i) {
      const double v = 0.5 * (P(i, j) + P(j, i));
      P(i, j) = v;
      P(j, i) = v;
    }
  }
}

/// Gathers rows/columns of P given as 3-blocks starting at `starts` into a dense matrix.
template <int N>
Eigen::Matrix<double, 3 * N, 3 * N> gatherBlocks(const Eigen::MatrixXd& P, const int (&starts)[N]) {
  Eigen::Matrix<double, 3 * N, 3 * N> out;
  for (int a = 0; a < N; ++a) {
    for (int b = 0; b < N; ++b) out.template block<3, 3>(3 * a, 3 * b) = P.block<3, 3>(starts[a], starts[b]);
  }
  return out;
}

}  // namespace vi_ekf_slam
