// The dynamic initializer's estimation problem: the window's velocity, gravity and accelerometer
// bias y = [v_0, g, b_a] (in the first body frame {I0}; b_a in the body) and every selected
// feature's position p_f in {I0}, from the tracks and the IMU increments. With the attitude from
// the gyro and the IMU's position increments alpha_k (A_k = d alpha_k / d b_a), the camera at
// frame k sees feature f at
//   p_c = R_c_k (p_f - v_0 t_k - g t_k^2 / 2 - alpha_k - A_k b_a) - R_b_c^T p_b_c.
// Stages (each a method, used in this order by the initializer):
// - solveLinear: each normalized observation (x, y) gives two equations linear in (p_f, v_0, g)
//   (b_a = 0): p_c.x - x p_c.z = 0, p_c.y - y p_c.z = 0; |g| imposed by a Lagrange multiplier.
// - refine: Levenberg-Marquardt on the reprojection error (Huber), with b_a under its prior and
//   |g| on its sphere (the linear solution is biased: errors in variables), features the linear
//   solution put behind the camera placed again and rejoined.
// - linearize(1, 0) at the solution: the normal equations the uncertainty stage inverts.
// The features are eliminated feature by feature (Schur complement on y): O(features).
#pragma once

#include <deque>
#include <vector>

#include "vi_ekf_slam/core/dynamic_init/preintegration.h"
#include "vi_ekf_slam/core/dynamic_init/track_selection.h"
#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/measurement_model.h"
#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {
namespace alignment {

using VecY = Eigen::Matrix<double, 9, 1>;
using MatY = Eigen::Matrix<double, 9, 9>;
using Mat3Y = Eigen::Matrix<double, 3, 9>;

struct ProblemSettings {
  double gravity_mps2 = 9.81;           ///< |g| [m/s^2]
  double pixel_noise_px = 1.0;          ///< std-dev of a feature position [px]
  double accel_bias_sigma_mps2 = 0.05;  ///< the accelerometer bias's prior std-dev [m/s^2]
  double time_offset_sigma_s = 0.05;    ///< the time offset's prior std-dev around 0 [s]
  int min_features = 12;                ///< fewer features in front of the camera: no solution [count]
};

class AlignmentProblem {
 public:
  /// stamps: the window's frames on the IMU clock (as the frames were stamped), oldest first;
  /// tracks: observations indexed into them. `imu` must outlive the problem.
  AlignmentProblem(const std::deque<ImuData>& imu, std::vector<double> stamps, std::vector<Track> tracks,
                   const CameraModel& camera, const CameraExtrinsics& T_b_c, const ProblemSettings& settings);

  /// The frames shifted by dt on the IMU clock, and the IMU integrated to them.
  void setTimeShift(double dt);
  /// The linear alignment with the frames shifted by dt (every feature); returns the reprojection
  /// error sum [px^2], or infinity when it has no solution.
  double solveLinear(double dt);
  /// The refined alignment at a time shift dt; returns its (Huber) reprojection cost plus the time
  /// offset's prior [px^2]. choose_active: from the linear solution, with the features it puts in
  /// front of the camera, then every other feature placed for the refined y and refined again
  /// until none joins. Otherwise (costs at several dt compare on the same features): from the last
  /// refinement, with the same features.
  double refine(double dt, bool choose_active = false);
  /// Levenberg-Marquardt on the active features from the current y and p_f; returns the cost.
  double levenbergMarquardt();
  /// Feature j placed for the current y alone: true (and kept) if in front of every camera with
  /// its depth determined.
  bool placeFeature(int j);
  /// Whether the window's parallax gives feature j's inverse depth (in its last camera) at pf to 50%.
  bool depthDetermined(int j, const Vec3& pf) const;
  /// Drops the active features whose depth is not determined and refines at dt again, up to 5
  /// rounds; false when the refinement then fails.
  bool dropUndeterminedFeatures(double dt);

  /// The normal equations at (y, p_f) with rows scaled by `scale` (1: normalized coordinates, the
  /// focal length: pixels) and a Huber loss (0: none). Leaves the per-feature blocks in hff(),
  /// hfy(), bf(). False if a feature is behind a camera.
  bool linearize(double scale, double huber_px, MatY* Hyy, VecY* by);
  /// The Huber cost [px^2] of (yy, pf) over the active features, with the bias prior.
  double reprojectionCost(const VecY& yy, const std::vector<Vec3>& pf, double huber_px) const;
  /// The normal equations of y at the solution in normalized units with the features eliminated
  /// (the Schur complement S, kept with the features' inverse blocks); false as linearize.
  bool eliminateAtSolution();
  /// The preintegration with a gyro bias b_g taken off the rates (others as set), then linearize(1,
  /// 0); the problem's own preintegration and blocks are kept. *pre_last: the last frame's.
  bool linearizeWithGyroBias(const Vec3& b_g, VecY* by, std::vector<Vec3>* bf, Preintegrated* pre_last);

  /// The feature pf in the camera of frame k, for yy.
  Vec3 cameraPoint(int k, const Vec3& pf, const VecY& yy) const;
  /// ... integrated as P, t after the first frame.
  Vec3 cameraPointWith(const Preintegrated& P, double t, const Vec3& pf, const VecY& yy) const;
  /// The body position in {I0} at t after the first frame, integrated as P.
  static Vec3 bodyPosition(const Preintegrated& P, double t, const VecY& yy);
  int activeObservations() const;
  /// The reprojection error sum [px^2] and its row count over the active features; false if one
  /// is behind a camera.
  bool residuals(double* sum_sq, int* rows) const;

  const std::vector<Track>& tracks() const { return tracks_; }
  const std::vector<double>& times() const { return times_; }
  const std::vector<Preintegrated>& preintegrated() const { return pre_; }
  const VecY& y() const { return y_; }
  const std::vector<Vec3>& features() const { return p_f_; }
  bool active(int j) const { return active_[static_cast<size_t>(j)] != 0; }
  int numActive() const { return num_active_; }
  const MatY& schur() const { return S_; }
  const Mat3& hffInverse(int j) const { return Hff_inv_[static_cast<size_t>(j)]; }
  const Mat3Y& hfy(int j) const { return Hfy_[static_cast<size_t>(j)]; }
  const Mat3& cameraFromBody() const { return R_c_b_; }
  double focalPx() const { return f_px_; }
  const ProblemSettings& settings() const { return s_; }
  int size() const { return M_; }

 private:
  double biasPriorWeight(double scale) const;
  double timeOffsetPrior(double dt) const;
  /// The linear solution's two passes (the second weighted by the first's depths).
  bool linearPass(int pass);
  /// Marks the features in front of every camera at the linear solution active.
  void chooseInFront();

  const std::deque<ImuData>& imu_;
  std::vector<double> stamps_, times_;
  std::vector<Track> tracks_;
  ProblemSettings s_;
  Mat3 R_c_b_;
  Vec3 p_c_b_;  ///< the body origin in the camera
  double f_px_;
  double huber_px_;
  int M_;
  std::vector<Preintegrated> pre_;
  std::vector<Mat3> Hff_, Hff_inv_;
  std::vector<Mat3Y> Hfy_;
  std::vector<Vec3> bf_, p_f_;
  VecY y_ = VecY::Zero();
  MatY S_ = MatY::Zero();
  std::vector<char> active_;
  int num_active_;
};

}  // namespace alignment
}  // namespace vi_ekf_slam
