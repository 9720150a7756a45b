#include "vi_ekf_slam/eval/reference_comparison.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "vi_ekf_slam/eval/metrics.h"

namespace vi_ekf_slam::eval {

std::optional<Alignment> alignmentFromString(const std::string& s) {
  for (auto a : {Alignment::kSE3, Alignment::kPosYaw, Alignment::kSim3}) {
    if (toString(a) == s) return a;
  }
  return std::nullopt;
}

std::string toString(Alignment a) {
  switch (a) {
    case Alignment::kSE3:
      return "se3";
    case Alignment::kPosYaw:
      return "posyaw";
    case Alignment::kSim3:
      return "sim3";
  }
  return "unknown";
}

std::vector<io::StampedPose> referenceView(const std::vector<io::StampedPose>& body_poses,
                                           const std::optional<CameraExtrinsics>& T_b_c,
                                           const std::vector<double>* time_offsets_s) {
  if (time_offsets_s && time_offsets_s->size() != body_poses.size()) {
    throw std::invalid_argument("referenceView: one time offset per pose");
  }
  std::vector<io::StampedPose> out;
  out.reserve(body_poses.size());
  for (size_t i = 0; i < body_poses.size(); ++i) {
    io::StampedPose s = body_poses[i];
    s.cov.reset();
    if (T_b_c) {
      s.p = s.p + s.q * T_b_c->p_b_c;
      s.q = (s.q * Quat(T_b_c->R_b_c)).normalized();
    }
    if (time_offsets_s) s.t -= (*time_offsets_s)[i];
    out.push_back(s);
  }
  return out;
}

ReferenceComparison compareWithReference(const std::vector<io::StampedPose>& estimate,
                                         const std::vector<io::StampedPose>& reference, Alignment alignment,
                                         double max_gap_s) {
  ReferenceComparison out;
  out.alignment = alignment;
  std::vector<Vec3> p_ref;
  std::vector<Quat> q_ref, q_est;
  for (const auto& e : estimate) {
    const std::optional<io::StampedPose> r = io::interpolatePose(reference, e.t, max_gap_s);
    if (!r) continue;
    out.t.push_back(e.t);
    out.estimate.push_back(e.p);
    q_est.push_back(e.q);
    p_ref.push_back(r->p);
    q_ref.push_back(r->q);
  }
  out.matched = static_cast<int>(out.t.size());
  if (out.matched < 3) {
    throw std::invalid_argument("compareWithReference: only " + std::to_string(out.matched) +
                                " estimates fall inside the reference's time span");
  }
  // As evo aligns (`evo_ape --align [--correct_scale]`): the estimate onto the reference,
  // p_ref ~ c R p_est + t; the residuals are in the reference's units, and in the estimate's metres
  // once divided by c (the reference units per metre).
  Mat3 R = Mat3::Identity();
  Vec3 t = Vec3::Zero();
  double c = 1.0;
  if (alignment == Alignment::kPosYaw) {
    const YawTranslation fit = alignPosYaw(out.estimate, p_ref);
    R = Eigen::AngleAxisd(fit.yaw, Vec3::UnitZ()).toRotationMatrix();
    t = fit.t;
  } else {
    Eigen::Matrix3Xd src(3, out.matched), dst(3, out.matched);
    for (int i = 0; i < out.matched; ++i) {
      src.col(i) = out.estimate[static_cast<size_t>(i)];
      dst.col(i) = p_ref[static_cast<size_t>(i)];
    }
    const Eigen::Matrix4d T = Eigen::umeyama(src, dst, alignment == Alignment::kSim3);
    c = T.block<3, 1>(0, 0).norm();
    R = T.topLeftCorner<3, 3>() / c;
    t = T.topRightCorner<3, 1>();
  }
  out.scale = c;
  std::vector<Vec3> e_p;
  std::vector<double> e_q;
  for (int i = 0; i < out.matched; ++i) {
    const size_t k = static_cast<size_t>(i);
    e_p.push_back(p_ref[k] - (c * R * out.estimate[k] + t));
    // The reference in the estimate's frame and metres, for plots beside the estimate.
    out.reference.push_back(R.transpose() * (p_ref[k] - t) / c);
    const Quat q_aligned = Quat(R) * q_est[k];
    e_q.push_back(orientationError(q_ref[k], q_aligned).norm() * 180.0 / M_PI);
  }
  out.position_rmse_reference_units = rms(e_p);
  out.position_rmse_m = out.position_rmse_reference_units / c;
  out.rotation_rmse_deg = rms(e_q);
  out.estimate_path_m = pathLength(out.estimate);
  out.reference_path_m = pathLength(out.reference);
  return out;
}

std::vector<WindowComparison> compareInWindows(const std::vector<io::StampedPose>& estimate,
                                               const std::vector<io::StampedPose>& reference, Alignment alignment,
                                               double window_s, double max_gap_s) {
  std::vector<WindowComparison> out;
  if (estimate.empty() || !(window_s > 0.0)) return out;
  const double start = estimate.front().t;
  size_t i = 0;
  for (double from = start; i < estimate.size(); from += window_s) {
    const double to = from + window_s;
    std::vector<io::StampedPose> part;
    for (; i < estimate.size() && estimate[i].t < to; ++i) part.push_back(estimate[i]);
    try {
      out.push_back({from, to, compareWithReference(part, reference, alignment, max_gap_s)});
    } catch (const std::invalid_argument&) {
      // fewer than three matches: no alignment to speak of
    }
  }
  return out;
}

double firstWindowScaleRatio(const std::vector<WindowComparison>& windows) {
  if (windows.size() < 2) return std::nan("");
  std::vector<double> later;
  for (size_t k = 1; k < windows.size(); ++k) later.push_back(windows[k].comparison.scale);
  std::nth_element(later.begin(), later.begin() + static_cast<std::ptrdiff_t>(later.size() / 2), later.end());
  double median = later[later.size() / 2];
  if (later.size() % 2 == 0) {
    median = 0.5 *
             (median + *std::max_element(later.begin(), later.begin() + static_cast<std::ptrdiff_t>(later.size() / 2)));
  }
  return windows.front().comparison.scale / median;
}

}  // namespace vi_ekf_slam::eval
