#include "vi_ekf_slam/core/dynamic_initializer.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "vi_ekf_slam/core/so3.h"
#include "vi_ekf_slam/core/static_initializer.h"

namespace vi_ekf_slam {

std::string DynamicInitParams::validate() const {
  std::ostringstream err;
  if (!(window_s > 0.1 && window_s <= 10.0)) err << "dynamic init window_s [s] must be in (0.1, 10]\n";
  if (min_frames < 3) err << "dynamic init min_frames must be >= 3\n";
  if (min_observations < 3) err << "dynamic init min_observations must be >= 3\n";
  if (min_features < 6) err << "dynamic init min_features must be >= 6\n";
  if (!(max_velocity_sigma_mps > 0.0)) err << "dynamic init max_velocity_sigma_mps [m/s] must be > 0\n";
  if (!(max_tilt_sigma_rad > 0.0)) err << "dynamic init max_tilt_sigma_rad [rad] must be > 0\n";
  if (!(gyro_bias_sigma_radps > 0.0)) err << "dynamic init gyro_bias_sigma_radps [rad/s] must be > 0\n";
  if (!(pixel_noise_px > 0.0)) err << "dynamic init pixel_noise_px [px] must be > 0\n";
  if (!(gravity_mps2 > 9.0 && gravity_mps2 < 10.5)) err << "dynamic init gravity_mps2 must be in (9, 10.5)\n";
  return err.str();
}

DynamicInitializer::DynamicInitializer(const DynamicInitParams& params, const CameraModel& camera,
                                       const CameraExtrinsics& T_b_c)
    : params_(params), camera_(camera), T_b_c_(T_b_c) {}

void DynamicInitializer::reset() {
  imu_.clear();
  frames_.clear();
}

void DynamicInitializer::addImu(const ImuData& imu) {
  if (!std::isfinite(imu.timestamp) || !imu.wm.allFinite() || !imu.am.allFinite()) return;
  if (!imu_.empty() && imu.timestamp <= imu_.back().timestamp) return;
  imu_.push_back(imu);
  // Keep what the window can need (frames wait for the IMU to pass them).
  const double keep_from = imu.timestamp - params_.window_s - 1.0;
  while (imu_.size() > 2 && imu_[1].timestamp < keep_from) imu_.pop_front();
}

void DynamicInitializer::addFrame(const CameraFrame& frame) {
  if (!std::isfinite(frame.timestamp)) return;
  if (!frames_.empty() && frame.timestamp <= frames_.back().timestamp) return;
  frames_.push_back(frame);
  while (!frames_.empty() && frames_.front().timestamp < frame.timestamp - params_.window_s - 1.0) frames_.pop_front();
}

namespace {

/// IMU samples interpolated at time t (clamped to the buffer).
ImuData interpolate(const std::deque<ImuData>& imu, double t) {
  if (t <= imu.front().timestamp) return imu.front();
  if (t >= imu.back().timestamp) return imu.back();
  auto it = std::lower_bound(imu.begin(), imu.end(), t, [](const ImuData& d, double x) { return d.timestamp < x; });
  const ImuData& b = *it;
  const ImuData& a = *(it - 1);
  const double s = (t - a.timestamp) / (b.timestamp - a.timestamp);
  return {t, a.wm + s * (b.wm - a.wm), a.am + s * (b.am - a.am)};
}

/// Attitude R_I0_Ik and the position / velocity increments (in {I0}, gravity left out) at each of
/// the sorted times, from the first one.
struct Preintegrated {
  Mat3 R = Mat3::Identity();
  Vec3 alpha = Vec3::Zero();
  Vec3 beta = Vec3::Zero();
};

std::vector<Preintegrated> preintegrate(const std::deque<ImuData>& imu, const std::vector<double>& times) {
  std::vector<double> cuts;
  for (const auto& d : imu) {
    if (d.timestamp > times.front() && d.timestamp < times.back()) cuts.push_back(d.timestamp);
  }
  cuts.insert(cuts.end(), times.begin(), times.end());
  std::sort(cuts.begin(), cuts.end());
  std::vector<Preintegrated> out;
  Preintegrated cur;
  size_t next = 0;
  out.push_back(cur);
  ++next;
  for (size_t i = 1; i < cuts.size() && next < times.size(); ++i) {
    const double a = cuts[i - 1], b = cuts[i], dt = b - a;
    if (dt > 0.0) {
      const ImuData m = interpolate(imu, 0.5 * (a + b));  // midpoint rule
      const Mat3 R_mid = cur.R * expSO3(0.5 * dt * m.wm);
      const Vec3 acc = R_mid * m.am;
      cur.alpha += cur.beta * dt + 0.5 * acc * dt * dt;
      cur.beta += acc * dt;
      cur.R = cur.R * expSO3(dt * m.wm);
    }
    while (next < times.size() && times[next] <= b) {
      out.push_back(cur);
      ++next;
    }
  }
  while (out.size() < times.size()) out.push_back(cur);
  return out;
}

struct Obs {
  int frame;
  Eigen::Vector2d xn;  ///< normalized undistorted coordinates
  Eigen::Vector2d uv;  ///< pixel
};

}  // namespace

std::optional<DynamicInitResult> DynamicInitializer::tryInitialize(std::string* why) {
  auto fail = [&](const std::string& w) -> std::optional<DynamicInitResult> {
    if (why) *why = w;
    return std::nullopt;
  };
  if (imu_.size() < 2 || frames_.empty()) return fail("waiting for IMU and images");
  // Frames the IMU covers, in the last window_s.
  std::vector<const CameraFrame*> window;
  const double search = params_.time_offset_search_s;
  for (auto it = frames_.rbegin(); it != frames_.rend(); ++it) {
    if (it->timestamp + search > imu_.back().timestamp) continue;
    if (it->timestamp - search < imu_.front().timestamp) break;
    if (!window.empty() && window.back()->timestamp - it->timestamp > params_.window_s) break;
    window.insert(window.begin(), &*it);
  }
  if (static_cast<int>(window.size()) < params_.min_frames) {
    return fail("collecting images (" + std::to_string(window.size()) + " of " + std::to_string(params_.min_frames) +
                ")");
  }
  // A short span aligns poorly (velocity and gravity come from the curvature of the path): the
  // images must span the window (within 10%).
  if (window.back()->timestamp - window.front()->timestamp < 0.9 * params_.window_s) {
    return fail("collecting images (" + std::to_string(window.back()->timestamp - window.front()->timestamp) +
                " s of " + std::to_string(params_.window_s) + " s)");
  }
  std::vector<double> stamps, times;
  for (const auto* f : window) stamps.push_back(f->timestamp);
  std::vector<Preintegrated> pre;

  // Features seen often enough, longest tracks first (a bounded problem).
  std::map<std::int64_t, std::vector<Obs>> tracks;
  for (int k = 0; k < static_cast<int>(window.size()); ++k) {
    for (const auto& f : window[static_cast<size_t>(k)]->features) {
      Eigen::Vector2d xn;
      if (f.uv.allFinite() && camera_.pixelToNormalized(f.uv, &xn)) tracks[f.id].push_back({k, xn, f.uv});
    }
  }
  std::vector<const std::vector<Obs>*> used;
  std::map<const std::vector<Obs>*, std::int64_t> ids;
  for (const auto& [id, obs] : tracks) {
    if (static_cast<int>(obs.size()) >= params_.min_observations) {
      used.push_back(&obs);
      ids[&obs] = id;
    }
  }
  std::sort(used.begin(), used.end(), [&](const auto* a, const auto* b) {
    return a->size() != b->size() ? a->size() > b->size() : ids[a] < ids[b];
  });
  constexpr size_t kMaxFeatures = 80;
  if (used.size() > kMaxFeatures) used.resize(kMaxFeatures);
  if (static_cast<int>(used.size()) < params_.min_features) {
    return fail("too few features tracked through " + std::to_string(params_.min_observations) + " images (" +
                std::to_string(used.size()) + " of " + std::to_string(params_.min_features) + ")");
  }

  const Mat3 R_c_b = T_b_c_.R_b_c.transpose();
  const Vec3 p_c_b = -R_c_b * T_b_c_.p_b_c;  // the body origin in the camera
  const int M = static_cast<int>(used.size());
  using Mat36 = Eigen::Matrix<double, 3, 6>;
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  // Normal equations, p_f eliminated feature by feature (Schur complement on y = [v0, g]).
  std::vector<Mat3> Hff(M);
  std::vector<Mat36> Hfy(M);
  std::vector<Vec3> bf(M);
  std::vector<Vec3> p_f(M, Vec3::Zero());
  Vec6 y = Vec6::Zero();
  Mat6 S = Mat6::Zero();
  std::vector<Mat3> Hff_inv;
  const double G = params_.gravity_mps2;
  const double f_px = 0.5 * (camera_.intrinsics().fx + camera_.intrinsics().fy);
  auto cameraPoint = [&](int k, const Vec3& pf, const Vec6& yy) {
    const double t = times[static_cast<size_t>(k)] - times.front();
    const Preintegrated& P = pre[static_cast<size_t>(k)];
    const Vec3 p_k = yy.head<3>() * t + 0.5 * yy.tail<3>() * t * t + P.alpha;
    return Vec3(R_c_b * P.R.transpose() * (pf - p_k) + p_c_b);
  };
  // The alignment with the frames shifted by dt on the IMU clock; returns the reprojection error
  // sum [px^2], or infinity when it has no solution or puts a feature behind the camera.
  auto solve = [&](double dt) {
    times = stamps;
    for (auto& t : times) t += dt;
    pre = preintegrate(imu_, times);
    for (int pass = 0; pass < 2; ++pass) {
      Mat6 Hyy = Mat6::Zero();
      Vec6 by = Vec6::Zero();
      for (int j = 0; j < M; ++j) {
        Hff[j].setZero();
        Hfy[j].setZero();
        bf[j].setZero();
        for (const Obs& o : *used[static_cast<size_t>(j)]) {
          const double t = times[static_cast<size_t>(o.frame)] - times.front();
          const Preintegrated& P = pre[static_cast<size_t>(o.frame)];
          const Mat3 R_ck = R_c_b * P.R.transpose();
          // Rows scaled by 1 / depth (from the first pass) are errors in normalized coordinates.
          double w = 1.0;
          if (pass > 0) {
            const double z = cameraPoint(o.frame, p_f[j], y).z();
            w = 1.0 / std::max(z, 0.05);
          }
          Eigen::Matrix<double, 2, 3> E;
          E << 1.0, 0.0, -o.xn.x(), 0.0, 1.0, -o.xn.y();
          const Eigen::Matrix<double, 2, 3> Af = w * E * R_ck;
          Eigen::Matrix<double, 2, 6> Ay;
          Ay << -t * Af, -0.5 * t * t * Af;
          const Eigen::Vector2d b = w * E * (R_ck * P.alpha - p_c_b);
          Hff[j] += Af.transpose() * Af;
          Hfy[j] += Af.transpose() * Ay;
          bf[j] += Af.transpose() * b;
          Hyy += Ay.transpose() * Ay;
          by += Ay.transpose() * b;
        }
      }
      S = Hyy;
      Vec6 s = by;
      Hff_inv.assign(M, Mat3::Zero());
      for (int j = 0; j < M; ++j) {
        Hff_inv[j] = (Hff[j] + 1e-12 * Mat3::Identity()).inverse();
        S -= Hfy[j].transpose() * Hff_inv[j] * Hfy[j];
        s -= Hfy[j].transpose() * Hff_inv[j] * bf[j];
      }
      // |g| = G: v0 eliminated, then (S_g + lambda I) g = s_g with lambda such that |g| = G.
      const Mat3 Svv = S.topLeftCorner<3, 3>(), Svg = S.topRightCorner<3, 3>(), Sgg = S.bottomRightCorner<3, 3>();
      const Mat3 Svv_inv = (Svv + 1e-12 * Mat3::Identity()).inverse();
      const Mat3 Sg = Sgg - Svg.transpose() * Svv_inv * Svg;
      const Vec3 sg = s.tail<3>() - Svg.transpose() * Svv_inv * s.head<3>();
      const Eigen::SelfAdjointEigenSolver<Mat3> es(0.5 * (Sg + Sg.transpose()));
      const Vec3& d = es.eigenvalues();
      const Vec3 c = es.eigenvectors().transpose() * sg;
      auto norm2 = [&](double lambda) {
        double n = 0.0;
        for (int i = 0; i < 3; ++i) n += c(i) * c(i) / ((d(i) + lambda) * (d(i) + lambda));
        return n;
      };
      double lo = -d.minCoeff() + 1e-12 * (1.0 + std::abs(d.minCoeff()));
      double hi = -d.minCoeff() + c.norm() / G + 1.0;
      if (!(norm2(lo) > G * G)) lo = -d.minCoeff();  // degenerate: the bisection ends at the lower end
      for (int it = 0; it < 200; ++it) {
        const double mid = 0.5 * (lo + hi);
        (norm2(mid) > G * G ? lo : hi) = mid;
      }
      const double lambda = 0.5 * (lo + hi);
      Vec3 g = Vec3::Zero();
      for (int i = 0; i < 3; ++i) g += es.eigenvectors().col(i) * c(i) / (d(i) + lambda);
      if (!(g.norm() > 0.5 * G)) return std::numeric_limits<double>::infinity();
      g *= G / g.norm();
      y.head<3>() = Svv_inv * (s.head<3>() - Svg * g);
      y.tail<3>() = g;
      for (int j = 0; j < M; ++j) p_f[j] = Hff_inv[j] * (bf[j] - Hfy[j] * y);
      if (!y.allFinite()) return std::numeric_limits<double>::infinity();
    }
    double chi2 = 0.0;
    for (int j = 0; j < M; ++j) {
      for (const Obs& o : *used[static_cast<size_t>(j)]) {
        const Vec3 pc = cameraPoint(o.frame, p_f[j], y);
        if (!(pc.z() > 0.05)) return std::numeric_limits<double>::infinity();
        chi2 += ((pc.head<2>() / pc.z() - o.xn) * f_px).squaredNorm();
      }
    }
    return chi2;
  };
  // The camera-IMU time offset is part of the alignment: the best of a grid over
  // +-time_offset_search_s (5 ms steps), refined by a golden-section search between its neighbours.
  double best_dt = 0.0, dt_curvature = 0.0;  // d^2 chi2 / d dt^2 at the best [px^2/s^2]
  if (search > 0.0) {
    constexpr double kStep = 0.005;
    const int n = static_cast<int>(std::floor(search / kStep));
    std::vector<double> cost(static_cast<size_t>(2 * n + 1));
    for (int i = 0; i <= 2 * n; ++i) cost[static_cast<size_t>(i)] = solve((i - n) * kStep);
    const int best = static_cast<int>(std::min_element(cost.begin(), cost.end()) - cost.begin());
    best_dt = (best - n) * kStep;
    if (best > 0 && best < 2 * n) {
      const auto ib = static_cast<size_t>(best);
      const double a = cost[ib - 1], b = cost[ib], c2 = cost[ib + 1];
      const double den = a - 2.0 * b + c2;
      if (std::isfinite(den) && den > 0.0) dt_curvature = den / (kStep * kStep);
      const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
      double lo = best_dt - kStep, hi = best_dt + kStep;
      double x1 = hi - phi * (hi - lo), x2 = lo + phi * (hi - lo);
      double f1 = solve(x1), f2 = solve(x2);
      for (int it = 0; it < 12; ++it) {  // the bracket shrinks to 0.3% of 10 ms
        if (f1 < f2) {
          hi = x2;
          x2 = x1;
          f2 = f1;
          x1 = hi - phi * (hi - lo);
          f1 = solve(x1);
        } else {
          lo = x1;
          x1 = x2;
          f1 = f2;
          x2 = lo + phi * (hi - lo);
          f2 = solve(x2);
        }
      }
      best_dt = f1 < f2 ? x1 : x2;
    }
  }
  if (!std::isfinite(solve(best_dt))) {
    return fail("degenerate motion: the alignment has no solution with the features in front of the camera");
  }

  const double G2 = G * G;
  const double t_K = times.back() - times.front();
  // RMS kinematic acceleration over the window (with the gravity found), for the time offset's share.
  double accel_rms = 0.0;
  {
    int n = 0;
    Mat3 R = Mat3::Identity();
    for (size_t i = 1; i < imu_.size(); ++i) {
      const double a = imu_[i - 1].timestamp, b = imu_[i].timestamp;
      if (b <= times.front() || a >= times.back()) continue;
      const ImuData m = interpolate(imu_, 0.5 * (a + b));
      R = R * expSO3((b - a) * m.wm);
      accel_rms += (R * m.am + y.tail<3>()).squaredNorm();
      ++n;
    }
    accel_rms = n > 0 ? std::sqrt(accel_rms / n) : 0.0;
  }
  // Uncertainty of v_K = v0 + g t_K + beta_K and of gravity's direction for a given pixel noise.
  double sigma_v_ls = 0.0;  // the velocity's std-dev from the alignment alone
  auto sigmas = [&](double sigma_px, double* sigma_v, double* sigma_tilt) {
    const double sigma_n = sigma_px / f_px;
    const Mat6 cov_y = sigma_n * sigma_n * (S + 1e-12 * Mat6::Identity()).inverse();
    Eigen::Matrix<double, 3, 6> J_v;
    J_v << Mat3::Identity(), t_K * Mat3::Identity();
    const Mat3 cov_v = J_v * cov_y * J_v.transpose();
    const Vec3 u = y.tail<3>().normalized();
    const Mat3 Pperp = Mat3::Identity() - u * u.transpose();
    const Mat3 cov_tilt = Pperp * cov_y.bottomRightCorner<3, 3>() * Pperp / G2;
    const double var_v = std::max(0.0, Eigen::SelfAdjointEigenSolver<Mat3>(cov_v).eigenvalues().maxCoeff());
    const double var_tilt = std::max(0.0, Eigen::SelfAdjointEigenSolver<Mat3>(cov_tilt).eigenvalues().maxCoeff());
    // What the linear problem takes as known adds to that: the gyro bias tilts the integrated
    // attitude by up to b_g T (and gravity leaks into the velocity through it), and a camera-IMU
    // time offset t_d shifts every frame's pose by the motion over t_d (velocity error ~ a t_d).
    const double tilt_bg = params_.gyro_bias_sigma_radps * t_K;
    // The time offset as found (Fisher information of chi2 / sigma^2: half its curvature), not
    // below the 5 ms grid, or as assumed when not searched.
    double td_sigma = params_.time_offset_sigma_s;
    if (search > 0.0)
      td_sigma = dt_curvature > 0.0 ? std::max(0.005, sigma_px * std::sqrt(2.0 / dt_curvature)) : search;
    const double v_td = accel_rms * td_sigma;
    *sigma_tilt = std::sqrt(var_tilt + tilt_bg * tilt_bg);
    sigma_v_ls = std::sqrt(var_v);
    *sigma_v = std::sqrt(var_v + std::pow(0.5 * G * tilt_bg, 2) + v_td * v_td);
  };
  std::ostringstream quality;
  quality.precision(3);
  auto observable = [&](double sigma_v, double sigma_tilt) {
    if (!(sigma_v <= params_.max_velocity_sigma_mps)) {
      quality << "degenerate motion: velocity known to " << sigma_v << " m/s only (more than "
              << params_.max_velocity_sigma_mps << "): too little acceleration or parallax";
      return false;
    }
    if (!(sigma_tilt <= params_.max_tilt_sigma_rad)) {
      quality << "degenerate motion: roll/pitch known to " << sigma_tilt << " rad only (more than "
              << params_.max_tilt_sigma_rad << ")";
      return false;
    }
    return true;
  };
  double sigma_v = 0.0, sigma_tilt = 0.0;
  sigmas(params_.pixel_noise_px, &sigma_v, &sigma_tilt);
  if (!observable(sigma_v, sigma_tilt)) return fail(quality.str());

  // Reprojection residuals and depths.
  double sum_sq = 0.0;
  int rows = 0;
  std::vector<double> last_depths;
  for (int j = 0; j < M; ++j) {
    for (const Obs& o : *used[static_cast<size_t>(j)]) {
      const Vec3 pc = cameraPoint(o.frame, p_f[j], y);
      if (!(pc.z() > 0.05)) return fail("alignment puts a feature behind the camera: wrong tracks or IMU");
      const Eigen::Vector2d e = (pc.head<2>() / pc.z() - o.xn) * f_px;
      sum_sq += e.squaredNorm();
      rows += 2;
      if (o.frame + 1 == static_cast<int>(times.size())) last_depths.push_back(pc.z());
    }
  }
  DynamicInitResult r;
  r.frames = static_cast<int>(times.size());
  r.features = M;
  r.residual_rms_px = std::sqrt(sum_sq / std::max(1, rows));
  if (r.residual_rms_px > 5.0 * params_.pixel_noise_px) {
    quality << "alignment residual " << r.residual_rms_px << " px: tracks or IMU inconsistent";
    return fail(quality.str());
  }
  // The noise the residuals show, if more than the assumed pixel noise, scales the uncertainty.
  const int dof = std::max(1, rows - (3 * M + 6));
  const double sigma_px = std::max(params_.pixel_noise_px, std::sqrt(sum_sq / dof));
  sigmas(sigma_px, &sigma_v, &sigma_tilt);
  if (!observable(sigma_v, sigma_tilt)) return fail(quality.str());
  const Vec3 g = y.tail<3>();
  const Preintegrated& PK = pre.back();
  const Quat q_n_I0 = gravityAlignedAttitude(-g);
  r.state.timestamp = times.back();
  r.time_offset_correction_s = best_dt;
  r.state.q_n_b = (q_n_I0 * Quat(PK.R)).normalized();
  r.state.v_n_b = q_n_I0 * (y.head<3>() + g * t_K + PK.beta);
  if (!last_depths.empty()) {
    std::nth_element(last_depths.begin(), last_depths.begin() + static_cast<std::ptrdiff_t>(last_depths.size() / 2),
                     last_depths.end());
    r.median_depth_m = last_depths[last_depths.size() / 2];
  }
  // The features of the last frame, with the depth uncertainty of the alignment (the marginal of
  // each p_f), scaled up as the velocity's by what the alignment takes as known (a scale error).
  const double inflate = sigma_v_ls > 0.0 ? sigma_v / sigma_v_ls : 1.0;
  const Mat6 S_inv = (S + 1e-12 * Mat6::Identity()).inverse();
  const double sigma_n2 = std::pow(sigma_px / f_px, 2);
  const int last = static_cast<int>(times.size()) - 1;
  const Mat3 R_cK = R_c_b * PK.R.transpose();
  for (int j = 0; j < M; ++j) {
    const std::vector<Obs>& obs = *used[static_cast<size_t>(j)];
    if (obs.back().frame != last) continue;
    const Vec3 pc = cameraPoint(last, p_f[j], y);
    const Mat3 cov_f = sigma_n2 * (Hff_inv[j] + Hff_inv[j] * Hfy[j] * S_inv * Hfy[j].transpose() * Hff_inv[j]);
    const double var_z = (R_cK * cov_f * R_cK.transpose())(2, 2);
    DynamicInitLandmark l;
    l.id = ids[&obs];
    l.uv = obs.back().uv;
    l.depth_m = pc.z();
    l.inverse_depth_sigma = inflate * std::sqrt(std::max(0.0, var_z)) / (pc.z() * pc.z());
    r.landmarks.push_back(l);
  }
  r.velocity_sigma_mps = sigma_v;
  r.tilt_sigma_rad = sigma_tilt;
  r.gyro_bias_sigma_radps = params_.gyro_bias_sigma_radps;
  if (why) why->clear();
  return r;
}

}  // namespace vi_ekf_slam
