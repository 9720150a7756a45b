#include "vi_ekf_slam/core/imu_sample_check.h"

#include <sstream>

#include "vi_ekf_slam/core/param_ranges.h"

namespace vi_ekf_slam {

std::string ImuCheckParams::validate() const {
  std::ostringstream err;
  checkRange(err, "imu_accel_range_mps2", accel_range_mps2);
  checkRange(err, "imu_gyro_range_radps", gyro_range_radps);
  checkRange(err, "imu_max_accel_step_mps2", max_accel_step_mps2);
  checkRange(err, "imu_max_gyro_step_radps", max_gyro_step_radps);
  checkRange(err, "imu_max_bridged_samples", max_bridged_samples);
  return err.str();
}

ImuSampleVerdict ImuSampleCheck::check(const ImuData& imu, const ImuCheckParams& p) {
  auto atRange = [](const Vec3& v, double range) { return range > 0.0 && v.cwiseAbs().maxCoeff() >= 0.999 * range; };
  auto jumped = [](const Vec3& v, const Vec3& ref, double step) {
    return step > 0.0 && (v - ref).cwiseAbs().maxCoeff() > step;
  };
  ImuSampleVerdict verdict = ImuSampleVerdict::kGood;
  if (atRange(imu.am, p.accel_range_mps2) || atRange(imu.wm, p.gyro_range_radps)) {
    verdict = ImuSampleVerdict::kClipped;
  } else if (last_good_ && (jumped(imu.am, last_good_->am, p.max_accel_step_mps2) ||
                            jumped(imu.wm, last_good_->wm, p.max_gyro_step_radps))) {
    verdict = ImuSampleVerdict::kImplausible;
  }
  if (verdict != ImuSampleVerdict::kGood && bridged_ < p.max_bridged_samples) {
    ++bridged_;
    return verdict;
  }
  // Good, or left out too long in a row: a real change of level (or a saturated stretch, which no
  // bridge can span) is taken as it is.
  bridged_ = 0;
  last_good_ = imu;
  return ImuSampleVerdict::kGood;
}

}  // namespace vi_ekf_slam
