// TUM trajectory files: one pose a line, `t x y z qx qy qz qw` (body in world; spaces or commas),
// `#` comments.
// Estimates may append the upper triangle of the 6x6 pose covariance (21 numbers, order
// [position, orientation]).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "vi_ekf_slam/core/so3.h"

namespace vi_ekf_slam::eval {

struct StampedPose {
  double t = 0.0;
  Vec3 p = Vec3::Zero();
  Quat q = Quat::Identity();
  std::optional<Eigen::Matrix<double, 6, 6>> cov;
};

/// Reads a TUM file; a line repeating the line before (same time, same pose) is skipped. Throws
/// std::runtime_error naming the file and line for malformed input (wrong column count,
/// non-numbers, non-finite values, zero quaternion, decreasing time, two poses at one time, a
/// time above 1e12 s: nanoseconds).
std::vector<StampedPose> readTum(const std::string& path);

/// The pose of a time-sorted sequence at time t: a pose whose stamp agrees within 1 us, else
/// interpolated (linear position, slerp) between the two poses around t if they are at most
/// max_gap_s apart; nullopt outside the sequence or across a longer gap.
std::optional<StampedPose> interpolatePose(const std::vector<StampedPose>& poses, double t, double max_gap_s);

/// Writes poses (with the covariance columns when every pose has one).
void writeTum(const std::string& path, const std::vector<StampedPose>& poses, const std::string& header = "");

}  // namespace vi_ekf_slam::eval
