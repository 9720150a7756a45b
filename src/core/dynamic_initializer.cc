#include "vi_ekf_slam/core/dynamic_initializer.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "vi_ekf_slam/core/so3.h"
#include "vi_ekf_slam/core/param_ranges.h"
#include "vi_ekf_slam/core/static_initializer.h"

namespace vi_ekf_slam {

std::string DynamicInitParams::validate() const {
  std::ostringstream err;
  checkRange(err, "dynamic_init_window_s", window_s);
  checkRange(err, "dynamic_init_max_window_s", max_window_s);
  checkRange(err, "dynamic_init_min_frames", min_frames);
  checkRange(err, "dynamic_init_min_observations", min_observations);
  checkRange(err, "dynamic_init_min_features", min_features);
  checkRange(err, "dynamic_init_max_velocity_sigma_mps", max_velocity_sigma_mps);
  checkRange(err, "dynamic_init_max_tilt_sigma_rad", max_tilt_sigma_rad);
  checkRange(err, "dynamic_init_max_scale_sigma", max_scale_sigma);
  checkRange(err, "dynamic_init_gyro_bias_sigma_radps", gyro_bias_sigma_radps);
  checkRange(err, "dynamic_init_accel_bias_sigma_mps2", accel_bias_sigma_mps2);
  checkRange(err, "pixel_noise_px", pixel_noise_px);
  checkRange(err, "gravity_mps2", gravity_mps2);
  return err.str();
}

DynamicInitParams withFilterSettings(DynamicInitParams p, const EkfSlamConfig& filter) {
  p.pixel_noise_px = filter.update.pixel_noise_px;
  p.time_offset_sigma_s = filter.initial.time_offset_s;
  p.accel_bias_sigma_mps2 = filter.initial.accel_bias_mps2;
  p.gravity_mps2 = filter.gravity_mps2;
  return p;
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
  const double keep_from = imu.timestamp - std::max(params_.window_s, params_.max_window_s) - 1.0;
  while (imu_.size() > 2 && imu_[1].timestamp < keep_from) imu_.pop_front();
}

void DynamicInitializer::addFrame(const CameraFrame& frame) {
  if (!std::isfinite(frame.timestamp)) return;
  if (!frames_.empty() && frame.timestamp <= frames_.back().timestamp) return;
  frames_.push_back(frame);
  const double keep_s = std::max(params_.window_s, params_.max_window_s) + 1.0;
  while (!frames_.empty() && frames_.front().timestamp < frame.timestamp - keep_s) frames_.pop_front();
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
  Mat3 A = Mat3::Zero();  ///< d alpha / d b_a (exact: alpha is linear in the accelerometer bias)
  Mat3 B = Mat3::Zero();  ///< d beta / d b_a
};

/// b_g: a gyro bias taken off the rates (the alignment's sensitivity to it).
std::vector<Preintegrated> preintegrate(const std::deque<ImuData>& imu, const std::vector<double>& times,
                                        const Vec3& b_g = Vec3::Zero()) {
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
      const Vec3 w = m.wm - b_g;
      const Mat3 R_mid = cur.R * expSO3(0.5 * dt * w);
      const Vec3 acc = R_mid * m.am;
      cur.alpha += cur.beta * dt + 0.5 * acc * dt * dt;
      cur.beta += acc * dt;
      cur.A += cur.B * dt - 0.5 * R_mid * dt * dt;
      cur.B -= R_mid * dt;
      cur.R = cur.R * expSO3(dt * w);
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

std::vector<const CameraFrame*> DynamicInitializer::coveredFrames(double span_s) const {
  std::vector<const CameraFrame*> window;
  if (imu_.size() < 2) return window;
  const double search = params_.time_offset_search_s;
  for (auto it = frames_.rbegin(); it != frames_.rend(); ++it) {
    if (it->timestamp + search > imu_.back().timestamp) continue;
    if (it->timestamp - search < imu_.front().timestamp) break;
    if (!window.empty() && window.back()->timestamp - it->timestamp > span_s) break;
    window.insert(window.begin(), &*it);
  }
  return window;
}

std::optional<DynamicInitResult> DynamicInitializer::tryInitialize(std::string* why) {
  std::string first_why;
  bool degenerate = false;
  std::optional<DynamicInitResult> r = alignSpan(params_.window_s, &first_why, &degenerate);
  if (!r && degenerate && params_.max_window_s > params_.window_s) {
    // Too little motion in the window: the frames before it may hold the acceleration it lacks.
    const std::vector<const CameraFrame*> longer = coveredFrames(params_.max_window_s);
    const double span = longer.empty() ? 0.0 : longer.back()->timestamp - longer.front()->timestamp;
    if (span > 1.1 * params_.window_s) {
      std::string longer_why;
      r = alignSpan(span, &longer_why, nullptr);
      if (!r) {
        std::ostringstream w;
        w.precision(3);
        w << first_why << "; over " << span << " s: " << longer_why;
        first_why = w.str();
      }
    }
  }
  if (why) *why = r ? std::string() : first_why;
  return r;
}

std::optional<DynamicInitResult> DynamicInitializer::alignSpan(double span_s, std::string* why, bool* degenerate) {
  auto fail = [&](const std::string& w) -> std::optional<DynamicInitResult> {
    if (why) *why = w;
    return std::nullopt;
  };
  // The window's motion leaves the state unobservable (a longer window may not).
  auto failDegenerate = [&](const std::string& w) {
    if (degenerate) *degenerate = true;
    return fail(w);
  };
  if (imu_.size() < 2 || frames_.empty()) return fail("waiting for IMU and images");
  const std::vector<const CameraFrame*> window = coveredFrames(span_s);
  const double search = params_.time_offset_search_s;
  if (static_cast<int>(window.size()) < params_.min_frames) {
    return fail("collecting images (" + std::to_string(window.size()) + " of " + std::to_string(params_.min_frames) +
                ")");
  }
  // A short span aligns poorly (velocity and gravity come from the curvature of the path): the
  // images must span the window (within 10%).
  if (window.back()->timestamp - window.front()->timestamp < 0.9 * span_s) {
    return fail("collecting images (" + std::to_string(window.back()->timestamp - window.front()->timestamp) +
                " s of " + std::to_string(span_s) + " s)");
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
  // y = [v0, g, b_a]: the velocity and gravity in {I0} and the accelerometer bias (body, with
  // its prior accel_bias_sigma_mps2: a real IMU's bias along gravity, 0.12 m/s^2 on the hand-held
  // rig, would otherwise scale a slow walk's path by tens of percent).
  using Mat3Y = Eigen::Matrix<double, 3, 9>;
  using MatY = Eigen::Matrix<double, 9, 9>;
  using VecY = Eigen::Matrix<double, 9, 1>;
  // Normal equations, p_f eliminated feature by feature (Schur complement on y).
  std::vector<Mat3> Hff(M);
  std::vector<Mat3Y> Hfy(M);
  std::vector<Vec3> bf(M);
  std::vector<Vec3> p_f(M, Vec3::Zero());
  VecY y = VecY::Zero();
  MatY S = MatY::Zero();
  std::vector<Mat3> Hff_inv;
  const double G = params_.gravity_mps2;
  const double f_px = 0.5 * (camera_.intrinsics().fx + camera_.intrinsics().fy);
  // The accelerometer bias's prior as a weight on the normal equations whose unit is the
  // residual's times `scale` (1: normalized coordinates, f_px: pixels).
  const double ba_sigma = std::max(1e-6, params_.accel_bias_sigma_mps2);
  auto biasPriorWeight = [&](double scale) { return std::pow(scale * params_.pixel_noise_px / f_px / ba_sigma, 2); };
  // The body position in {I0} of a frame t after the first, integrated as P.
  auto bodyPosition = [&](const Preintegrated& P, double t, const VecY& yy) {
    return Vec3(yy.head<3>() * t + 0.5 * yy.segment<3>(3) * t * t + P.alpha + P.A * yy.tail<3>());
  };
  // The feature pf in the camera of a frame t after the first, integrated as P.
  auto cameraPointWith = [&](const Preintegrated& P, double t, const Vec3& pf, const VecY& yy) {
    return Vec3(R_c_b * P.R.transpose() * (pf - bodyPosition(P, t, yy)) + p_c_b);
  };
  // d (x / z, y / z) / d pc of a point pc in the camera.
  auto projectionJacobian = [](const Vec3& pc) {
    Eigen::Matrix<double, 2, 3> Jp;
    Jp << 1.0 / pc.z(), 0.0, -pc.x() / (pc.z() * pc.z()), 0.0, 1.0 / pc.z(), -pc.y() / (pc.z() * pc.z());
    return Jp;
  };
  auto cameraPoint = [&](int k, const Vec3& pf, const VecY& yy) {
    return cameraPointWith(pre[static_cast<size_t>(k)], times[static_cast<size_t>(k)] - times.front(), pf, yy);
  };
  // The frames shifted by dt on the IMU clock, and the IMU integrated to them.
  auto setTimes = [&](double dt) {
    times = stamps;
    for (auto& t : times) t += dt;
    pre = preintegrate(imu_, times);
  };
  // The linear alignment with the frames shifted by dt; returns the reprojection error sum
  // [px^2], or infinity when it has no solution.
  auto solve = [&](double dt) {
    setTimes(dt);
    for (int pass = 0; pass < 2; ++pass) {
      MatY Hyy = MatY::Zero();
      VecY by = VecY::Zero();
      // The bias stays 0 here (it is barely observable in the linear problem, whose bias would
      // feed it): the refinement estimates it.
      Hyy.bottomRightCorner<3, 3>().diagonal().setConstant(1e12);
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
          Eigen::Matrix<double, 2, 9> Ay;
          Ay << -t * Af, -0.5 * t * t * Af, -Af * P.A;
          const Eigen::Vector2d b = w * E * (R_ck * P.alpha - p_c_b);
          Hff[j] += Af.transpose() * Af;
          Hfy[j] += Af.transpose() * Ay;
          bf[j] += Af.transpose() * b;
          Hyy += Ay.transpose() * Ay;
          by += Ay.transpose() * b;
        }
      }
      S = Hyy;
      VecY s = by;
      Hff_inv.assign(M, Mat3::Zero());
      for (int j = 0; j < M; ++j) {
        Hff_inv[j] = (Hff[j] + 1e-12 * Mat3::Identity()).inverse();
        S -= Hfy[j].transpose() * Hff_inv[j] * Hfy[j];
        s -= Hfy[j].transpose() * Hff_inv[j] * bf[j];
      }
      // |g| = G: o = [v0, b_a] eliminated, then (S_g + lambda I) g = s_g with lambda such that |g| = G.
      using Mat6 = Eigen::Matrix<double, 6, 6>;
      using Mat63 = Eigen::Matrix<double, 6, 3>;
      Mat6 Soo;
      Soo << S.topLeftCorner<3, 3>(), S.topRightCorner<3, 3>(), S.bottomLeftCorner<3, 3>(), S.bottomRightCorner<3, 3>();
      Mat63 Sog;
      Sog << S.block<3, 3>(0, 3), S.block<3, 3>(6, 3);
      Eigen::Matrix<double, 6, 1> so;
      so << s.head<3>(), s.tail<3>();
      const Mat6 Soo_inv = (Soo + 1e-12 * Mat6::Identity()).inverse();
      const Mat3 Sg = S.block<3, 3>(3, 3) - Sog.transpose() * Soo_inv * Sog;
      const Vec3 sg = s.segment<3>(3) - Sog.transpose() * Soo_inv * so;
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
      const Eigen::Matrix<double, 6, 1> yo = Soo_inv * (so - Sog * g);
      y << yo.head<3>(), g, yo.tail<3>();
      for (int j = 0; j < M; ++j) p_f[j] = Hff_inv[j] * (bf[j] - Hfy[j] * y);
      if (!y.allFinite()) return std::numeric_limits<double>::infinity();
    }
    // The reprojection error; a feature the linear solution puts behind the camera counts with its
    // algebraic error over 5 cm (large, but finite: the search keeps its slope there).
    double chi2 = 0.0;
    for (int j = 0; j < M; ++j) {
      for (const Obs& o : *used[static_cast<size_t>(j)]) {
        const Vec3 pc = cameraPoint(o.frame, p_f[j], y);
        chi2 += ((pc.head<2>() - o.xn * pc.z()) * f_px / std::max(pc.z(), 0.05)).squaredNorm();
      }
    }
    return chi2;
  };
  // Features the linear solution puts behind the camera (far, seen with little parallax) stay out
  // of the refinement and the result.
  std::vector<char> active(static_cast<size_t>(M), 1);
  int num_active = M;
  // The linear solution is biased: its equations multiply the noisy measurement by the unknown
  // depth (errors in variables), which pulls the scale, hence the velocity, down (-25% on a
  // simulated walk with 1 px noise). Levenberg-Marquardt on the reprojection error in pixels,
  // from there, with |g| held on its sphere (a 2-dof tangent step) and a Huber loss, removes it.
  // linearize() also leaves the normal equations in normalized units at the solution (weights 1),
  // which the uncertainty below uses.
  auto linearize = [&](double scale, double huber_px, MatY* Hyy, VecY* by) {
    Hyy->setZero();
    by->setZero();
    Hyy->bottomRightCorner<3, 3>().diagonal().setConstant(biasPriorWeight(scale));
    by->tail<3>() = biasPriorWeight(scale) * y.tail<3>();
    for (int j = 0; j < M; ++j) {
      Hff[j].setZero();
      Hfy[j].setZero();
      bf[j].setZero();
      if (!active[static_cast<size_t>(j)]) continue;
      for (const Obs& o : *used[static_cast<size_t>(j)]) {
        const double t = times[static_cast<size_t>(o.frame)] - times.front();
        const Mat3 R_ck = R_c_b * pre[static_cast<size_t>(o.frame)].R.transpose();
        const Vec3 pc = cameraPoint(o.frame, p_f[j], y);
        if (!(pc.z() > 0.05)) return false;
        const Eigen::Vector2d e = scale * (pc.head<2>() / pc.z() - o.xn);
        const Eigen::Matrix<double, 2, 3> Jp = projectionJacobian(pc);
        const Eigen::Matrix<double, 2, 3> Jf = scale * Jp * R_ck;
        Eigen::Matrix<double, 2, 9> Jy;
        Jy << -t * Jf, -0.5 * t * t * Jf, -Jf * pre[static_cast<size_t>(o.frame)].A;
        const double w = huber_px > 0.0 && e.norm() > huber_px ? huber_px / e.norm() : 1.0;
        Hff[j] += w * Jf.transpose() * Jf;
        Hfy[j] += w * Jf.transpose() * Jy;
        bf[j] += w * Jf.transpose() * e;
        *Hyy += w * Jy.transpose() * Jy;
        *by += w * Jy.transpose() * e;
      }
    }
    return true;
  };
  auto reprojectionCost = [&](const VecY& yy, const std::vector<Vec3>& pf, double huber_px) {
    double cost = biasPriorWeight(f_px) * yy.tail<3>().squaredNorm();
    for (int j = 0; j < M; ++j) {
      if (!active[static_cast<size_t>(j)]) continue;
      for (const Obs& o : *used[static_cast<size_t>(j)]) {
        const Vec3 pc = cameraPoint(o.frame, pf[static_cast<size_t>(j)], yy);
        if (!(pc.z() > 0.05)) return std::numeric_limits<double>::infinity();
        const double e = ((pc.head<2>() / pc.z() - o.xn) * f_px).norm();
        cost += e <= huber_px ? e * e : huber_px * (2.0 * e - huber_px);
      }
    }
    return cost;
  };
  const double huber_px = 3.0 * params_.pixel_noise_px;
  // The time offset's prior (time_offset_sigma_s around the configured offset) in the cost: with
  // little motion the images hardly tell the offset, and a free search wanders to its bounds.
  auto timeOffsetPrior = [&](double dt) {
    return std::pow(params_.pixel_noise_px * dt / std::max(1e-6, params_.time_offset_sigma_s), 2);
  };
  // The alignment at a time shift dt, refined; returns its (Huber) reprojection cost [px^2].
  // choose_active: the features used are those in front of the camera at this dt (costs at
  // several dt compare on the same features: chosen once, at the grid's best).
  auto activeObservations = [&]() {
    int k = 0;
    for (int j = 0; j < M; ++j)
      k += active[static_cast<size_t>(j)] ? static_cast<int>(used[static_cast<size_t>(j)]->size()) : 0;
    return k;
  };
  // Levenberg-Marquardt on the active features from the current y and p_f; returns the cost.
  auto levenbergMarquardt = [&]() {
    double cost = reprojectionCost(y, p_f, huber_px), lambda = 1e-4;
    for (int it = 0; it < 20 && std::isfinite(cost); ++it) {
      MatY Hyy;
      VecY by;
      if (!linearize(f_px, huber_px, &Hyy, &by)) break;
      // g on its sphere: steps in the plane normal to it.
      const Vec3 u = y.segment<3>(3).normalized();
      const Vec3 a = std::abs(u.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
      Eigen::Matrix<double, 9, 8> T = Eigen::Matrix<double, 9, 8>::Zero();
      T.topLeftCorner<3, 3>().setIdentity();
      T.block<3, 1>(3, 3) = u.cross(a).normalized();
      T.block<3, 1>(3, 4) = u.cross(T.block<3, 1>(3, 3));
      T.bottomRightCorner<3, 3>().setIdentity();
      bool accepted = false;
      for (int tries = 0; tries < 8 && !accepted; ++tries) {
        MatY Sy = Hyy;
        VecY sy = by;
        std::vector<Mat3> Hinv(static_cast<size_t>(M));
        for (int j = 0; j < M; ++j) {
          if (!active[static_cast<size_t>(j)]) continue;
          Mat3 D = Hff[j];
          D.diagonal() *= 1.0 + lambda;
          Hinv[static_cast<size_t>(j)] = (D + 1e-12 * Mat3::Identity()).inverse();
          Sy -= Hfy[j].transpose() * Hinv[static_cast<size_t>(j)] * Hfy[j];
          sy -= Hfy[j].transpose() * Hinv[static_cast<size_t>(j)] * bf[j];
        }
        Eigen::Matrix<double, 8, 8> S8 = T.transpose() * Sy * T;
        S8.diagonal() *= 1.0 + lambda;
        const Eigen::Matrix<double, 8, 1> d8 = -S8.ldlt().solve(T.transpose() * sy);
        const VecY dy = T * d8;
        VecY y_new = y + dy;
        y_new.segment<3>(3) = G * y_new.segment<3>(3).normalized();
        std::vector<Vec3> pf_new = p_f;
        for (int j = 0; j < M; ++j) {
          if (active[static_cast<size_t>(j)])
            pf_new[static_cast<size_t>(j)] -= Hinv[static_cast<size_t>(j)] * (bf[j] + Hfy[j] * dy);
        }
        const double c = y_new.allFinite() ? reprojectionCost(y_new, pf_new, huber_px) : cost + 1.0;
        if (c < cost) {
          const double gain = (cost - c) / cost;
          y = y_new;
          p_f = pf_new;
          cost = c;
          lambda = std::max(1e-8, 0.1 * lambda);
          accepted = true;
          if (gain < 1e-8) it = 1000;  // converged
        } else {
          lambda *= 10.0;
        }
      }
      if (!accepted) break;
    }
    return cost;
  };
  // Whether the window's parallax gives feature j's inverse depth rho = 1 / z (in its last camera)
  // to 50% at pf for the current y: a point the window cannot tell from one at infinity says
  // nothing of y, and its position (x, y, z) is then far from linear in the observations. The
  // information is taken along its ray from the last camera (pf = c_K + m / rho), finite for a point
  // the refinement has pushed far out, where the Cartesian normal equations are singular.
  auto depthDetermined = [&](int j, const Vec3& pf) {
    const std::vector<Obs>& obs = *used[static_cast<size_t>(j)];
    const int k = obs.back().frame;
    const Mat3 R_cK = R_c_b * pre[static_cast<size_t>(k)].R.transpose();
    const Vec3 pc_K = cameraPoint(k, pf, y);
    const double z = pc_K.z();
    if (!(z > 0.05)) return false;
    const double rho = 1.0 / z;
    const Vec3 dpf_drho = -R_cK.transpose() * (pc_K / z) / (rho * rho);
    double info = 0.0;
    for (const Obs& o : obs) {
      const Vec3 pc = cameraPoint(o.frame, pf, y);
      const Mat3 R_ck = R_c_b * pre[static_cast<size_t>(o.frame)].R.transpose();
      const Vec3 d = R_ck * dpf_drho;
      info +=
          (Eigen::Vector2d(d.x() - pc.x() / pc.z() * d.z(), d.y() - pc.y() / pc.z() * d.z()) / pc.z()).squaredNorm();
    }
    const double sigma_rho = params_.pixel_noise_px / f_px / std::sqrt(std::max(info, 1e-300));
    return sigma_rho < 0.5 * rho;
  };
  // Feature j placed for the current y alone (y fixed): the linear triangulation of its rays, then
  // Gauss-Newton on its reprojection error; true if it is then in front of every camera and its
  // depth determined (above).
  auto placeFeature = [&](int j) {
    const std::vector<Obs>& obs = *used[static_cast<size_t>(j)];
    Mat3 H = Mat3::Zero();
    Vec3 b = Vec3::Zero();
    for (const Obs& o : obs) {
      const double t = times[static_cast<size_t>(o.frame)] - times.front();
      const Preintegrated& P = pre[static_cast<size_t>(o.frame)];
      const Mat3 R_ck = R_c_b * P.R.transpose();
      const Vec3 p_k = bodyPosition(P, t, y);
      Eigen::Matrix<double, 2, 3> E;
      E << 1.0, 0.0, -o.xn.x(), 0.0, 1.0, -o.xn.y();
      const Eigen::Matrix<double, 2, 3> Af = E * R_ck;
      H += Af.transpose() * Af;
      b += Af.transpose() * (E * (R_ck * p_k - p_c_b));
    }
    Vec3 pf = (H + 1e-12 * Mat3::Identity()).ldlt().solve(b);
    for (int it = 0; it < 5; ++it) {
      Mat3 Hj = Mat3::Zero();
      Vec3 bj = Vec3::Zero();
      for (const Obs& o : obs) {
        const Vec3 pc = cameraPoint(o.frame, pf, y);
        if (!(pc.z() > 0.05)) return false;
        const Mat3 R_ck = R_c_b * pre[static_cast<size_t>(o.frame)].R.transpose();
        const Eigen::Matrix<double, 2, 3> Jp = projectionJacobian(pc);
        const Eigen::Matrix<double, 2, 3> Jf = Jp * R_ck;
        Hj += Jf.transpose() * Jf;
        bj += Jf.transpose() * (pc.head<2>() / pc.z() - o.xn);
      }
      pf -= (Hj + 1e-12 * Mat3::Identity()).ldlt().solve(bj);
    }
    for (const Obs& o : obs) {
      if (!(cameraPoint(o.frame, pf, y).z() > 0.05)) return false;
    }
    if (!depthDetermined(j, pf)) return false;
    p_f[static_cast<size_t>(j)] = pf;
    return true;
  };
  // The alignment at a time shift dt, refined; returns its (Huber) reprojection cost [px^2] plus
  // the time offset's prior. choose_active: from the linear solution, with the features it puts
  // in front of the camera; then every other feature placed for the refined y (the linear
  // solution can be far enough off to put most of a window's features behind the camera, and a
  // refinement on the few it kept only confirms it) and refined again, until none joins.
  // Otherwise (costs at several dt compare on the same features): from the last refinement.
  auto refine = [&](double dt, bool choose_active = false) {
    if (choose_active) {
      if (!std::isfinite(solve(dt))) return std::numeric_limits<double>::infinity();
      num_active = 0;
      for (int j = 0; j < M; ++j) {
        bool in_front = true;
        for (const Obs& o : *used[static_cast<size_t>(j)]) {
          in_front = in_front && cameraPoint(o.frame, p_f[j], y).z() > 0.05;
        }
        active[static_cast<size_t>(j)] = in_front;
        num_active += in_front;
      }
    } else {
      setTimes(dt);
    }
    if (num_active < params_.min_features) return std::numeric_limits<double>::infinity();
    double cost = levenbergMarquardt();
    for (int round = 0; choose_active && std::isfinite(cost) && round < 3; ++round) {
      int joined = 0;
      for (int j = 0; j < M; ++j) {
        if (!active[static_cast<size_t>(j)] && placeFeature(j)) {
          active[static_cast<size_t>(j)] = 1;
          ++joined;
        }
      }
      if (joined == 0) break;
      num_active += joined;
      cost = levenbergMarquardt();
    }
    return cost + timeOffsetPrior(dt);
  };
  // The camera-IMU time offset is part of the alignment: the best of the refined alignments on a
  // 10 ms grid over +-time_offset_search_s, then a golden-section search over +-10 ms around it.
  // (The linear solution's cost is no guide: its bias moves its best by tens of ms with 1 px noise,
  // into a minimum the refinement cannot leave.) Grid points compare by their cost per
  // observation, as each keeps the features in front of the camera there.
  double best_dt = 0.0, dt_curvature = 0.0;  // d^2 cost / d dt^2 at the best [px^2/s^2]
  if (search > 0.0) {
    constexpr double kStep = 0.01;
    const int n = static_cast<int>(std::floor(search / kStep));
    double best_score = std::numeric_limits<double>::infinity();
    for (int i = -n; i <= n; ++i) {
      const double c = refine(i * kStep, true);
      const double score = c / std::max(1, activeObservations());
      if (score < best_score) {
        best_score = score;
        best_dt = i * kStep;
      }
    }
    refine(best_dt, true);
    const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
    double lo = std::max(-search, best_dt - kStep), hi = std::min(search, best_dt + kStep);
    double x1 = hi - phi * (hi - lo), x2 = lo + phi * (hi - lo);
    double f1 = refine(x1), f2 = refine(x2);
    for (int it = 0; it < 12; ++it) {  // the bracket shrinks to 0.3% of 20 ms
      if (f1 < f2) {
        hi = x2;
        x2 = x1;
        f2 = f1;
        x1 = hi - phi * (hi - lo);
        f1 = refine(x1);
      } else {
        lo = x1;
        x1 = x2;
        f1 = f2;
        x2 = lo + phi * (hi - lo);
        f2 = refine(x2);
      }
    }
    best_dt = f1 < f2 ? x1 : x2;
    const double fb = std::min(f1, f2), fa = refine(best_dt - kStep), fc = refine(best_dt + kStep);
    const double den = fa - 2.0 * fb + fc;
    if (std::isfinite(den) && den > 0.0) dt_curvature = den / (kStep * kStep);
  }
  if (search <= 0.0) refine(0.0, true);
  if (!std::isfinite(refine(best_dt))) {
    return failDegenerate("degenerate motion: the alignment has no solution with the features in front of the camera");
  }
  // A feature whose depth the refined window leaves undetermined (pushed far out along its ray)
  // leaves the alignment: its Cartesian normal equations are singular and would make up a
  // covariance for it and for y.
  for (int round = 0;; ++round) {
    int dropped = 0;
    for (int j = 0; j < M; ++j) {
      if (active[static_cast<size_t>(j)] && !depthDetermined(j, p_f[j])) {
        active[static_cast<size_t>(j)] = 0;
        --num_active;
        ++dropped;
      }
    }
    if (dropped == 0) break;
    if (round == 4 || !std::isfinite(refine(best_dt))) {
      return failDegenerate("degenerate motion: too few features whose depth the window determines");
    }
  }
  {
    MatY Hyy;
    VecY by;
    if (!linearize(1.0, 0.0, &Hyy, &by)) {
      return fail("alignment puts a feature behind the camera: wrong tracks or IMU");
    }
    S = Hyy;
    for (int j = 0; j < M; ++j) {
      if (!active[static_cast<size_t>(j)]) continue;
      Hff_inv[static_cast<size_t>(j)] = (Hff[j] + 1e-12 * Mat3::Identity()).inverse();
      S -= Hfy[j].transpose() * Hff_inv[static_cast<size_t>(j)] * Hfy[j];
    }
  }

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
      accel_rms += (R * (m.am - y.tail<3>()) + y.segment<3>(3)).squaredNorm();
      ++n;
    }
    accel_rms = n > 0 ? std::sqrt(accel_rms / n) : 0.0;
  }
  // The state the alignment gives at the last frame: attitude (gravity-aligned, yaw of {I0} kept),
  // velocity in {n} and the accelerometer bias, as functions of y; yaw_ref removes the heading a
  // change of g would give (the heading is not the alignment's to know).
  const Preintegrated PK = pre.back();
  struct Out {
    Quat q_n_b;
    Vec3 v_n;
  };
  auto outputWith = [&](const VecY& yy, const Preintegrated& pk, const Quat* q_ref) {
    const Quat q_n_I0 = gravityAlignedAttitude(-yy.segment<3>(3));
    Out o;
    o.q_n_b = (q_n_I0 * Quat(pk.R)).normalized();
    o.v_n = q_n_I0 * (yy.head<3>() + yy.segment<3>(3) * t_K + pk.beta + pk.B * yy.tail<3>());
    if (q_ref) {
      const Quat unyaw(Eigen::AngleAxisd(-yawBetween(*q_ref, o.q_n_b), Vec3::UnitZ()));
      o.q_n_b = unyaw * o.q_n_b;
      o.v_n = unyaw * o.v_n;
    }
    return o;
  };
  const Out y_out = outputWith(y, PK, nullptr);
  // [v_n, psi_n] of op minus om, over 2h (psi_n: R_true = Exp(psi) R_est; its yaw row is zero).
  auto outputDifference = [&](const Out& op, const Out& om, double h) {
    Eigen::Matrix<double, 6, 1> d;
    d.head<3>() = (op.v_n - om.v_n) / (2.0 * h);
    d.tail<3>() = (logSO3((op.q_n_b * y_out.q_n_b.conjugate()).toRotationMatrix()) -
                   logSO3((om.q_n_b * y_out.q_n_b.conjugate()).toRotationMatrix())) /
                  (2.0 * h);
    d(5) = 0.0;
    return d;
  };
  // d [v_n, psi_n, b_a] / d y, numerically.
  Eigen::Matrix<double, 9, 9> J_out = Eigen::Matrix<double, 9, 9>::Zero();
  for (int i = 0; i < 9; ++i) {
    const double h = i < 3 ? 1e-4 : i < 6 ? 1e-4 * G : 1e-4;
    VecY yp = y, ym = y;
    yp(i) += h;
    ym(i) -= h;
    J_out.block<6, 1>(0, i) = outputDifference(outputWith(yp, PK, &y_out.q_n_b), outputWith(ym, PK, &y_out.q_n_b), h);
  }
  J_out.block<3, 3>(6, 6).setIdentity();
  const MatY S_inv = (S + 1e-12 * MatY::Identity()).inverse();
  // The gyro bias is not estimated (a 1 s window hardly observes it) but not known either: it
  // turns every integrated attitude, so it moves the whole solution, the velocity, the tilt and
  // every depth together. Its share, to first order (a "consider" parameter, Schmidt): the
  // solution's sensitivity d theta / d b_g = -H^-1 d grad / d b_g, the gradient of the normal
  // equations at the solution differenced over b_g, plus the output's own dependence on it.
  constexpr double kBgStep = 1e-4;  // [rad/s]
  Eigen::Matrix<double, 9, 3> dy_dbg = Eigen::Matrix<double, 9, 3>::Zero();
  std::vector<Mat3> dpf_dbg(static_cast<size_t>(M), Mat3::Zero());
  Eigen::Matrix<double, 9, 3> dout_dbg = Eigen::Matrix<double, 9, 3>::Zero();
  std::array<std::array<Preintegrated, 2>, 3> PK_bg;  // the last frame's, at +-kBgStep per axis
  {
    const std::vector<Preintegrated> pre0 = pre;
    const std::vector<Mat3> Hff0 = Hff;
    const std::vector<Mat3Y> Hfy0 = Hfy;
    for (int k = 0; k < 3; ++k) {
      std::array<std::vector<Vec3>, 2> bfs;
      std::array<VecY, 2> bys;
      bool ok = true;
      for (int sgn = 0; sgn < 2; ++sgn) {
        pre = preintegrate(imu_, times, (sgn == 0 ? kBgStep : -kBgStep) * Vec3::Unit(k));
        PK_bg[static_cast<size_t>(k)][static_cast<size_t>(sgn)] = pre.back();
        MatY H;
        ok = ok && linearize(1.0, 0.0, &H, &bys[static_cast<size_t>(sgn)]);
        bfs[static_cast<size_t>(sgn)] = bf;
      }
      if (!ok) continue;
      std::vector<Vec3> dbf(static_cast<size_t>(M), Vec3::Zero());
      VecY rhs = (bys[0] - bys[1]) / (2.0 * kBgStep);
      for (int j = 0; j < M; ++j) {
        if (!active[static_cast<size_t>(j)]) continue;
        dbf[static_cast<size_t>(j)] =
            (bfs[0][static_cast<size_t>(j)] - bfs[1][static_cast<size_t>(j)]) / (2.0 * kBgStep);
        rhs -= Hfy0[static_cast<size_t>(j)].transpose() * Hff_inv[static_cast<size_t>(j)] * dbf[static_cast<size_t>(j)];
      }
      dy_dbg.col(k) = -S_inv * rhs;
      for (int j = 0; j < M; ++j) {
        if (!active[static_cast<size_t>(j)]) continue;
        dpf_dbg[static_cast<size_t>(j)].col(k) =
            -Hff_inv[static_cast<size_t>(j)] *
            (dbf[static_cast<size_t>(j)] + Hfy0[static_cast<size_t>(j)] * dy_dbg.col(k));
      }
      dout_dbg.block<6, 1>(0, k) =
          outputDifference(outputWith(y, PK_bg[static_cast<size_t>(k)][0], &y_out.q_n_b),
                           outputWith(y, PK_bg[static_cast<size_t>(k)][1], &y_out.q_n_b), kBgStep);
    }
    dout_dbg += J_out * dy_dbg;
    pre = pre0;
    Hff = Hff0;
    Hfy = Hfy0;
  }
  const double bg_var = params_.gyro_bias_sigma_radps * params_.gyro_bias_sigma_radps;
  // The covariance of [v_n, psi_n, b_a] for a given pixel noise, and the largest std-devs of the
  // velocity and of roll/pitch.
  double sigma_v_ls = 0.0;  // the velocity's std-dev without the time offset's and the bound's shares
  Eigen::Matrix<double, 9, 9> cov_out;
  auto sigmas = [&](double sigma_px, double* sigma_v, double* sigma_tilt) {
    const double sigma_n = sigma_px / f_px;
    const MatY cov_y = sigma_n * sigma_n * (S + 1e-12 * MatY::Identity()).inverse();
    cov_out = J_out * cov_y * J_out.transpose() + bg_var * dout_dbg * dout_dbg.transpose();
    sigma_v_ls = std::sqrt(
        std::max(0.0, Eigen::SelfAdjointEigenSolver<Mat3>(cov_out.topLeftCorner<3, 3>()).eigenvalues().maxCoeff()));
    // A camera-IMU time offset t_d shifts every frame's pose by the motion over t_d (velocity
    // error ~ a t_d): the offset as found (Fisher information of cost / sigma^2: half its
    // curvature), not below 1 ms, or as assumed when not searched.
    double td_sigma = params_.time_offset_sigma_s;
    if (search > 0.0)
      td_sigma = dt_curvature > 0.0 ? std::max(0.001, sigma_px * std::sqrt(2.0 / dt_curvature)) : search;
    const double v_td = accel_rms * td_sigma;
    // What the first-order terms leave out (the IMU's own noise over the window, the
    // linearization) is kept as the bound the alignment had before its gyro-bias share was
    // computed: a tilt of b_g T and the gravity it leaks into the velocity. Without it, the
    // simulated EuRoC starts (seed 3 of make initsuite) left the NEES band (7.64 against 6.41).
    const double tilt_bg = params_.gyro_bias_sigma_radps * t_K;
    cov_out.topLeftCorner<3, 3>().diagonal().array() += v_td * v_td + std::pow(0.5 * G * tilt_bg, 2);
    cov_out.block<2, 2>(3, 3).diagonal().array() += tilt_bg * tilt_bg;
    *sigma_v = std::sqrt(
        std::max(0.0, Eigen::SelfAdjointEigenSolver<Mat3>(cov_out.topLeftCorner<3, 3>()).eigenvalues().maxCoeff()));
    *sigma_tilt = std::sqrt(std::max(
        0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(cov_out.block<2, 2>(3, 3)).eigenvalues().maxCoeff()));
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
  if (!observable(sigma_v, sigma_tilt)) return failDegenerate(quality.str());

  // Reprojection residuals and depths.
  double sum_sq = 0.0;
  int rows = 0;
  std::vector<double> last_depths;
  for (int j = 0; j < M; ++j) {
    if (!active[static_cast<size_t>(j)]) continue;
    for (const Obs& o : *used[static_cast<size_t>(j)]) {
      const Vec3 pc = cameraPoint(o.frame, p_f[j], y);
      if (!(pc.z() > 0.05)) return fail("alignment puts a feature behind the camera: wrong tracks or IMU");
      const Eigen::Vector2d e = (pc.head<2>() / pc.z() - o.xn) * f_px;
      sum_sq += e.squaredNorm();
      rows += 2;
    }
  }
  DynamicInitResult r;
  r.frames = static_cast<int>(times.size());
  r.features = num_active;
  r.residual_rms_px = std::sqrt(sum_sq / std::max(1, rows));
  if (r.residual_rms_px > 5.0 * params_.pixel_noise_px) {
    quality << "alignment residual " << r.residual_rms_px << " px: tracks or IMU inconsistent";
    return fail(quality.str());
  }
  // The noise the residuals show, if more than the assumed pixel noise, scales the uncertainty.
  const int dof = std::max(1, rows - (3 * num_active + 5));
  const double sigma_px = std::max(params_.pixel_noise_px, std::sqrt(sum_sq / dof));
  sigmas(sigma_px, &sigma_v, &sigma_tilt);
  if (!observable(sigma_v, sigma_tilt)) return failDegenerate(quality.str());
  r.state.timestamp = times.back();
  r.time_offset_correction_s = best_dt;
  r.state.q_n_b = y_out.q_n_b;
  r.state.v_n_b = y_out.v_n;
  r.state.b_a = y.tail<3>();
  r.covariance = cov_out;
  // The features of the last frame with their inverse depth rho = 1 / z in the last camera. To
  // first order rho_j = g_j dy + a_j e_j: a_j = d rho / d p_f, e_j the feature's own error (p_f
  // given y; covariance sigma^2 Hff^-1) and g_j the share of the window's [v0, g, b_a] error dy
  // (covariance sigma^2 S^-1), through the feature (p_f follows y by -Hff^-1 Hfy dy) and through
  // the last camera's position p_K(y). The shared part is the scale: taken as independent per
  // landmark, tens of landmarks would "know" it several times better than the alignment does.
  // Scaled up as the velocity by the time offset's and the bound's shares (a scale error); the
  // gyro bias's share as above, through p_f, y and the last frame's attitude and position.
  const double inflate = sigma_v_ls > 0.0 ? sigma_v / sigma_v_ls : 1.0;
  const double sigma_n2 = std::pow(sigma_px / f_px, 2);
  const int last = static_cast<int>(times.size()) - 1;
  const Mat3 R_cK = R_c_b * PK.R.transpose();
  Mat3Y dpK_dy;  // d p_K / d y
  dpK_dy << t_K * Mat3::Identity(), 0.5 * t_K * t_K * Mat3::Identity(), PK.A;
  std::vector<Eigen::Matrix<double, 1, 9>> shared;
  std::vector<Eigen::RowVector3d> from_bg;  // d rho / d b_g
  std::vector<double> own_var;
  for (int j = 0; j < M; ++j) {
    const std::vector<Obs>& obs = *used[static_cast<size_t>(j)];
    if (!active[static_cast<size_t>(j)] || obs.back().frame != last) continue;
    const Vec3 pc = cameraPoint(last, p_f[j], y);
    const Eigen::RowVector3d a = -R_cK.row(2) / (pc.z() * pc.z());
    shared.push_back(-a * dpK_dy - a * Hff_inv[j] * Hfy[j]);
    own_var.push_back(sigma_n2 * a * Hff_inv[j] * a.transpose());
    Eigen::RowVector3d d = a * dpf_dbg[static_cast<size_t>(j)] - a * dpK_dy * dy_dbg;
    for (int k = 0; k < 3; ++k) {
      std::array<double, 2> rho{};
      for (int sgn = 0; sgn < 2; ++sgn) {
        const Preintegrated& pk = PK_bg[static_cast<size_t>(k)][static_cast<size_t>(sgn)];
        rho[static_cast<size_t>(sgn)] = 1.0 / cameraPointWith(pk, t_K, p_f[j], y).z();
      }
      d(k) += (rho[0] - rho[1]) / (2.0 * kBgStep);
    }
    from_bg.push_back(d);
    DynamicInitLandmark l;
    l.id = ids[&obs];
    l.uv = obs.back().uv;
    l.depth_m = pc.z();
    r.landmarks.push_back(l);
  }
  const int n = static_cast<int>(r.landmarks.size());
  Eigen::Matrix<double, Eigen::Dynamic, 9> Gs(n, 9);
  Eigen::Matrix<double, Eigen::Dynamic, 3> Bs(n, 3);
  for (int i = 0; i < n; ++i) {
    Gs.row(i) = shared[static_cast<size_t>(i)];
    Bs.row(i) = from_bg[static_cast<size_t>(i)];
  }
  r.landmark_covariance = inflate * inflate * sigma_n2 * Gs * S_inv * Gs.transpose() + bg_var * Bs * Bs.transpose();
  for (int i = 0; i < n; ++i) r.landmark_covariance(i, i) += inflate * inflate * own_var[static_cast<size_t>(i)];
  r.landmark_state_covariance =
      inflate * sigma_n2 * Gs * S_inv * J_out.transpose() + bg_var * Bs * dout_dbg.transpose();
  r.landmark_gyro_bias_covariance = bg_var * Bs;
  r.gyro_bias_covariance = bg_var * dout_dbg;
  for (int i = 0; i < n; ++i) {
    DynamicInitLandmark& l = r.landmarks[static_cast<size_t>(i)];
    l.inverse_depth_sigma = std::sqrt(std::max(0.0, r.landmark_covariance(i, i)));
    // The scene's depth from the features whose depth the window determined (to 50%): without
    // parallax (a rig at rest) the depths are arbitrary.
    if (l.inverse_depth_sigma * l.depth_m < 0.5) last_depths.push_back(l.depth_m);
  }
  // The scale of the scene: the mean inverse depth of the last frame's features, whose error is
  // mostly the error they share (their own errors average out). A velocity known to 0.07 m/s is a
  // good start for a walk at 1.3 m/s and no start for a hand moving at 0.1 m/s: the velocity's
  // sigma is absolute, the scale's relative, and what a monocular start cannot do without.
  if (n == 0) return fail("no feature of the last image placed: nothing to give the scale");
  double mean_rho = 0.0;
  for (const DynamicInitLandmark& l : r.landmarks) mean_rho += 1.0 / l.depth_m;
  mean_rho /= n;
  r.scale_sigma = std::sqrt(std::max(0.0, r.landmark_covariance.sum())) / n / mean_rho;
  if (!(r.scale_sigma <= params_.max_scale_sigma)) {
    quality << "degenerate motion: the scene's scale known to " << 100.0 * r.scale_sigma << "% only (more than "
            << 100.0 * params_.max_scale_sigma << "%): too little acceleration for its depth";
    return failDegenerate(quality.str());
  }
  if (last_depths.size() >= 3) {
    std::nth_element(last_depths.begin(), last_depths.begin() + static_cast<std::ptrdiff_t>(last_depths.size() / 2),
                     last_depths.end());
    r.median_depth_m = last_depths[last_depths.size() / 2];
  }
  r.velocity_sigma_mps = sigma_v;
  r.tilt_sigma_rad = sigma_tilt;
  r.gyro_bias_sigma_radps = params_.gyro_bias_sigma_radps;
  r.accel_bias_sigma_mps2 = std::sqrt(
      std::max(0.0, Eigen::SelfAdjointEigenSolver<Mat3>(cov_out.bottomRightCorner<3, 3>()).eigenvalues().maxCoeff()));
  if (why) why->clear();
  return r;
}

}  // namespace vi_ekf_slam
