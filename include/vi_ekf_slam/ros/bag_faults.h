// Faulty copies of a bag, one fault class at a time, with its size as a parameter: what a first
// responder's rig meets (an IMU clipping at its range when bumped, a stalled cable or driver, a
// glove over the lens, corrupt samples, dim light, a lossy link). vi_ekf_slam_perturb_bag writes
// them; `make faults` runs the node's processor over each (docs/evaluation.md).
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "vi_ekf_slam/core/imu_sample_check.h"

namespace vi_ekf_slam::glue {

enum class FaultClass {
  kClippedImu,   ///< isolated IMU samples at the sensor's range, one every `size` s
  kSensorGaps,   ///< three IMU gaps of `size` s, two image gaps of 6 x `size` s
  kCoveredLens,  ///< black images for `size` s
  kNanImu,       ///< an IMU sample of NaN every `size` s
  kDimImages,    ///< `size` s of dim, noisy images (a fifth of the light, noise of 8 grey levels)
  kLossyLink,    ///< each image dropped with probability `size`, duplicated with `size` / 2, late by up to 30 ms
  kDarkness,     ///< `size` s of darkness: a twentieth of the light, the sensor's noise of 8 grey levels
};

std::optional<FaultClass> faultClassFromString(const std::string& s);
std::string toString(FaultClass c);
std::vector<FaultClass> allFaultClasses();
/// Where a class that acts at one moment of the bag acts unless FaultPlan::at_fraction places it
/// elsewhere, a fraction of the bag; none for a class that acts throughout.
std::optional<double> ownMoment(FaultClass c);
/// A class that acts at one moment of the bag (FaultPlan::at_fraction places it).
bool actsAtOneMoment(FaultClass c);
/// The classes that act at one moment with their own moments, "covered_lens (0.5), ...".
std::string momentFaultsList();
/// The size of a class as the tests and `make faults` use it by default (at least the sizes that
/// reset the filter on the real recording before these faults were handled).
double defaultFaultSize(FaultClass c);

struct FaultPlan {
  FaultClass fault = FaultClass::kClippedImu;
  double size = 0.0;  ///< see FaultClass [s, or a probability]
  std::uint64_t seed = 1;
  /// Where a fault of one moment (actsAtOneMoment) starts, as a fraction of the bag [0, 1);
  /// unset: the class's own moment (ownMoment).
  std::optional<double> at_fraction;
  /// The clipped value of an accelerometer and a gyro axis: the range the node assumes by default.
  double accel_range_mps2 = ImuCheckParams().accel_range_mps2;
  double gyro_range_radps = ImuCheckParams().gyro_range_radps;
};

/// What the copy holds that the original did not.
struct FaultCounts {
  int imu_clipped = 0, imu_dropped = 0, imu_nan = 0;
  int images_dropped = 0, images_black = 0, images_dim = 0, images_duplicated = 0,
      images_late = 0;                               ///< dim: darkness too
  std::vector<std::pair<double, double>> intervals;  ///< the faults' [start, end] in bag time [s]
};

/// `mono8` at `light` of its light under Gaussian noise of `noise_sigma` grey levels drawn from
/// `rng`, saturated to 8 bits: the images of dim_images and darkness (a high gain over a faint scene).
cv::Mat dimmed(const cv::Mat& mono8, double light, double noise_sigma, cv::RNG& rng);

/// Writes `out`, a copy of `in` with the fault applied to its IMU and image topics (chosen as
/// run_bag chooses them; raw or compressed images, written raw where their pixels change). Throws
/// std::runtime_error when the bag cannot be read or written.
FaultCounts perturbBag(const std::string& in, const std::string& out, const FaultPlan& plan);

}  // namespace vi_ekf_slam::glue
