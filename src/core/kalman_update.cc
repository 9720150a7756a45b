#include "vi_ekf_slam/core/kalman_update.h"

#include <cmath>
#include <limits>

#include "vi_ekf_slam/core/chi_squared.h"
#include "vi_ekf_slam/core/matrix_utils.h"

namespace vi_ekf_slam {

namespace {
/// The entries 0..n-1 not in `sorted` (ascending).
std::vector<int> complementOf(const std::vector<int>& sorted, int n) {
  std::vector<int> out;
  out.reserve(static_cast<size_t>(n) - sorted.size());
  size_t k = 0;
  for (int i = 0; i < n; ++i) {
    if (k < sorted.size() && sorted[k] == i) {
      ++k;
    } else {
      out.push_back(i);
    }
  }
  return out;
}
}  // namespace

void innovationCovariance(const Eigen::MatrixXd& P, const std::vector<MeasurementRows>& rows, Eigen::MatrixXd* PHt,
                          Eigen::MatrixXd* S) {
  int m = 0;
  for (const auto& r : rows) m += r.dim();
  PHt->resize(P.rows(), m);
  S->resize(m, m);
  int row = 0;
  for (const auto& r : rows) {
    auto cols = PHt->middleCols(row, r.dim());
    cols.setZero();
    for (const auto& b : r.blocks) cols.noalias() += P.middleCols(b.col, b.H.cols()) * b.H.transpose();
    row += r.dim();
  }
  row = 0;
  for (const auto& r : rows) {
    auto out = S->middleRows(row, r.dim());
    out.setZero();
    for (const auto& b : r.blocks) out.noalias() += b.H * PHt->middleRows(b.col, b.H.cols());
    out.middleCols(row, r.dim()).diagonal().array() += r.noise_var;
    row += r.dim();
  }
  symmetrize(*S);
}

Eigen::VectorXd applyJacobian(const std::vector<MeasurementRows>& rows, const Eigen::VectorXd& dx) {
  int m = 0;
  for (const auto& r : rows) m += r.dim();
  Eigen::VectorXd Hd = Eigen::VectorXd::Zero(m);
  int row = 0;
  for (const auto& r : rows) {
    for (const auto& b : r.blocks) Hd.segment(row, r.dim()) += b.H * dx.segment(b.col, b.H.cols());
    row += r.dim();
  }
  return Hd;
}

Eigen::VectorXd stackedResidual(const std::vector<MeasurementRows>& rows) {
  int m = 0;
  for (const auto& r : rows) m += r.dim();
  Eigen::VectorXd out(m);
  int row = 0;
  for (const auto& r : rows) {
    out.segment(row, r.dim()) = r.residual;
    row += r.dim();
  }
  return out;
}

double normalizedInnovation(const Eigen::MatrixXd& P, const MeasurementRows& rows) {
  const int k = rows.dim();
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3> S = rows.noise_var * Eigen::MatrixXd::Identity(k, k);
  for (const auto& a : rows.blocks) {
    for (const auto& b : rows.blocks) {
      S.noalias() += a.H * P.block(a.col, b.col, a.H.cols(), b.H.cols()) * b.H.transpose();
    }
  }
  const Eigen::LDLT<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3>> ldlt(S);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return std::numeric_limits<double>::infinity();
  const double d2 = rows.residual.dot(ldlt.solve(rows.residual));
  return std::isfinite(d2) ? d2 : std::numeric_limits<double>::infinity();
}

bool factorInnovation(const Eigen::MatrixXd& S, Eigen::LLT<Eigen::MatrixXd>* llt) {
  llt->compute(S);
  return llt->info() == Eigen::Success;
}

void optimalGainCovarianceUpdate(Eigen::MatrixXd& P, const Eigen::MatrixXd& PHt, const Eigen::LLT<Eigen::MatrixXd>& llt,
                                 const std::vector<int>& consider) {
  // A^T = L^-1 (P H^T)^T, so A A^T = P H^T S^-1 H P.
  const Eigen::MatrixXd At = llt.matrixL().solve(PHt.transpose());
  if (consider.empty()) {
    P.selfadjointView<Eigen::Lower>().rankUpdate(At.transpose(), -1.0);
    P.triangularView<Eigen::StrictlyUpper>() = P.transpose();
    return;
  }
  // With K = [K_a; 0], (I-KH) P (I-KH)^T + K R K^T differs from P - A A^T only in the consider
  // block, which keeps its prior: that block (the kept map's dormant points, most of the state) is
  // never computed, only the updated entries' own block and their cross-covariance with it.
  const std::vector<int> updated = complementOf(consider, static_cast<int>(P.rows()));
  const Eigen::MatrixXd A_u = At(Eigen::all, updated).transpose();
  const Eigen::MatrixXd A_c = At(Eigen::all, consider).transpose();
  Eigen::MatrixXd P_uu = P(updated, updated);
  P_uu.selfadjointView<Eigen::Lower>().rankUpdate(A_u, -1.0);
  P_uu.triangularView<Eigen::StrictlyUpper>() = P_uu.transpose();
  const Eigen::MatrixXd P_uc = P(updated, consider) - A_u * A_c.transpose();
  P(updated, updated) = P_uu;
  P(updated, consider) = P_uc;
  P(consider, updated) = P_uc.transpose();
}

void zeroConsider(Eigen::VectorXd& dx, const std::vector<int>& consider) {
  for (int k : consider) dx(k) = 0.0;
}

KalmanUpdateResult kalmanUpdate(FilterState& state, const std::vector<MeasurementRows>& rows, double gate_probability) {
  KalmanUpdateResult res;
  Eigen::MatrixXd PHt, S;
  innovationCovariance(state.covariance(), rows, &PHt, &S);
  Eigen::LLT<Eigen::MatrixXd> llt;
  if (!factorInnovation(S, &llt)) return res;
  const Eigen::VectorXd r = stackedResidual(rows);
  const Eigen::VectorXd Sinv_r = llt.solve(r);
  res.nis = r.dot(Sinv_r);
  if (!std::isfinite(res.nis)) return res;
  if (gate_probability > 0.0 && res.nis > chiSquaredQuantile(gate_probability, static_cast<double>(r.size()))) {
    return res;
  }
  const std::vector<int> consider = state.considerEntries();
  Eigen::VectorXd dx = PHt * Sinv_r;
  zeroConsider(dx, consider);
  optimalGainCovarianceUpdate(state.mutableCovariance(), PHt, llt, consider);
  state.boxplus(dx);
  res.applied = true;
  return res;
}

}  // namespace vi_ekf_slam
