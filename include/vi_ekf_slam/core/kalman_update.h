// The one EKF update step every measurement of the filter goes through. A measurement supplies
// its rows: the Jacobian as column blocks of the error state (H is sparse: a feature touches the
// pose, the time offset and its landmark; a zero-velocity update the velocity), its residual
// z - h(x) and its noise. This file does the rest: P H^T and the innovation covariance from the
// blocks (O(n m), H is never formed), the NIS, the chi-square gate, the gain and the covariance
// update. Adding a measurement is one builder of MeasurementRows and a call.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <vector>

#include "vi_ekf_slam/core/filter_state.h"

namespace vi_ekf_slam {

/// One non-zero block of a measurement's Jacobian: rows x width columns starting at column `col`.
struct JacobianBlock {
  int col = 0;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3> H;  ///< at most 3 x 3
};

/// A measurement of up to 3 rows: z - h(x) = sum_blocks H_b dx_b + v, v ~ N(0, noise_var I).
struct MeasurementRows {
  std::vector<JacobianBlock> blocks;
  Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1> residual;  ///< z - h(x)
  double noise_var = 1.0;                                      ///< per row [unit of z ^2]
  int dim() const { return static_cast<int>(residual.size()); }
};

/// P H^T (n x m) and S = H P H^T + R (m x m) of the stacked rows, from their blocks.
void innovationCovariance(const Eigen::MatrixXd& P, const std::vector<MeasurementRows>& rows, Eigen::MatrixXd* PHt,
                          Eigen::MatrixXd* S);
/// H dx of the stacked rows.
Eigen::VectorXd applyJacobian(const std::vector<MeasurementRows>& rows, const Eigen::VectorXd& dx);
/// The stacked residuals.
Eigen::VectorXd stackedResidual(const std::vector<MeasurementRows>& rows);
/// r^T S^-1 r of one measurement alone (its own S), for its gate; +inf if S is not positive definite.
double normalizedInnovation(const Eigen::MatrixXd& P, const MeasurementRows& rows);

/// The Cholesky factor of S (into *llt), through which the gain K = P H^T S^-1 acts (K itself,
/// n x m, is never formed: the correction is P H^T (S^-1 r)). False if S is not positive
/// definite: then nothing may be updated.
bool factorInnovation(const Eigen::MatrixXd& S, Eigen::LLT<Eigen::MatrixXd>* llt);
/// The covariance after an update with the optimal gain, P - P H^T S^-1 H P, as P - A A^T with
/// A = P H^T L^-T (S = L L^T, `llt` from factorInnovation): the Joseph form (I-KH) P (I-KH)^T + K R K^T
/// for that gain, in one symmetric rank-m product of which only the lower triangle is computed
/// and mirrored (P stays exactly symmetric). O(n^2 m / 2), half the expanded Joseph form's
/// O(n^2 m), which the state's size makes the update's largest cost once the map is kept.
/// `consider` (ascending error-state entries, FilterState::considerEntries): those entries get a
/// zero gain (Schmidt-Kalman), so their block of P stays as it was, and only their cross-covariance
/// with the rest is updated; the result is the Joseph form of that sub-optimal gain, exactly. Their
/// block is not computed at all: with nc of n entries considered the cost is O((n^2 - nc^2) m / 2).
void optimalGainCovarianceUpdate(Eigen::MatrixXd& P, const Eigen::MatrixXd& PHt, const Eigen::LLT<Eigen::MatrixXd>& llt,
                                 const std::vector<int>& consider = {});
/// Zeroes a correction's consider entries (their gain is zero).
void zeroConsider(Eigen::VectorXd& dx, const std::vector<int>& consider);

struct KalmanUpdateResult {
  bool applied = false;
  double nis = 0.0;  ///< r^T S^-1 r of the stacked rows (before the gate)
};

/// The whole step for a measurement linear in the error state: NIS, the gate (chi-square of the
/// stacked dimension at gate_probability; <= 0: none), gain, covariance update, and the correction
/// applied to the state (none to its consider landmarks).
KalmanUpdateResult kalmanUpdate(FilterState& state, const std::vector<MeasurementRows>& rows, double gate_probability);

}  // namespace vi_ekf_slam
