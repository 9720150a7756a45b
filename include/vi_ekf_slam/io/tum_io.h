// TUM trajectory files (io/: the files of trajectories and recordings, shared by the simulator
// and the evaluation): one pose a line, `t x y z qx qy qz qw` (body in world), `#` comments.
// Written as evo, ov_eval and rpg_trajectory_evaluation read them: 8 numbers separated by one
// space. The pose covariances go to a file of their own (writePoseCovariances): a TUM file with
// more columns is refused by evo and misread by ov_eval (which takes 20+ columns as an
// orientation-first covariance).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "vi_ekf_slam/core/so3.h"

namespace vi_ekf_slam::io {

struct StampedPose {
  double t = 0.0;
  Vec3 p = Vec3::Zero();
  Quat q = Quat::Identity();
  std::optional<Eigen::Matrix<double, 6, 6>> cov;
};

/// Reads a TUM file (spaces or commas between the 8 numbers); a line repeating the line before
/// (same time, same pose) is skipped. Throws std::runtime_error naming the file and line for
/// malformed input (wrong column count, non-numbers, non-finite values, zero quaternion, decreasing
/// time, two poses at one time, a time above 1e12 s: nanoseconds).
std::vector<StampedPose> readTum(const std::string& path);

/// The pose of a time-sorted sequence at time t: a pose whose stamp agrees within 1 us, else
/// interpolated (linear position, slerp) between the two poses around t if they are at most
/// max_gap_s apart; nullopt outside the sequence or across a longer gap.
std::optional<StampedPose> interpolatePose(const std::vector<StampedPose>& poses, double t, double max_gap_s);

/// Writes poses as 8 columns (the covariances, if any, are not written: writePoseCovariances).
void writeTum(const std::string& path, const std::vector<StampedPose>& poses, const std::string& header = "");

/// Writes `t` and the upper triangle of each pose's 6x6 covariance (21 numbers, row by row, order
/// [position [m], orientation [rad]]) for the poses that have one, one pose a line.
void writePoseCovariances(const std::string& path, const std::vector<StampedPose>& poses);
/// Reads such a file into the poses of `poses` with the same stamps (within 1 us); returns how
/// many got a covariance. Throws std::runtime_error for malformed lines.
int readPoseCovariances(const std::string& path, std::vector<StampedPose>* poses);

}  // namespace vi_ekf_slam::io
