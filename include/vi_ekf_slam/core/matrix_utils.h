// Small dense-matrix helpers that keep covariances well-formed.
#pragma once

#include <Eigen/Core>
#include <algorithm>

namespace vi_ekf_slam {

/// P <- (P + P^T) / 2 in place (no aliasing temporaries), in 32 x 32 tiles: the mirrored
/// element is a row away in memory, and a whole-column sweep missed the cache on every one of
/// them once the map is kept (P of several MB).
inline void symmetrize(Eigen::MatrixXd& P) {
  constexpr Eigen::Index kTile = 32;
  const Eigen::Index n = P.rows();
  for (Eigen::Index jb = 0; jb < n; jb += kTile) {
    const Eigen::Index j_end = std::min(n, jb + kTile);
    for (Eigen::Index ib = jb; ib < n; ib += kTile) {
      const Eigen::Index i_end = std::min(n, ib + kTile);
      for (Eigen::Index j = jb; j < j_end; ++j) {
        for (Eigen::Index i = std::max(ib, j + 1); i < i_end; ++i) {
          const double v = 0.5 * (P(i, j) + P(j, i));
          P(i, j) = v;
          P(j, i) = v;
        }
      }
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
