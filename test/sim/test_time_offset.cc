#include <gtest/gtest.h>

#include <cmath>

#include "vi_ekf_slam/sim/hallway.h"
#include "vi_ekf_slam/sim/scenarios.h"
#include "vi_ekf_slam/sim/sim_runner.h"

using namespace vi_ekf_slam;

namespace {

struct OffsetRun {
  double final_offset = 0.0, final_sigma = 0.0, final_error = 0.0;
  double offset_at_10s = 0.0;
};

/// The 35 s hallway walk with the camera stamped `true_offset` early against the IMU
/// (t_imu = t_image + true_offset), the filter started at `initial_offset` with `sigma`.
OffsetRun runWithOffset(double true_offset, double initial_offset, double sigma) {
  sim::Scenario sc = sim::hallwayScenario(sim::HallwayParams(), 1.0, 1);
  sc.cam.time_offset_s = true_offset;
  EkfSlamConfig c;
  c.imu_noise = sc.imu.noise;
  c.camera_time_offset_s = initial_offset;
  c.initial.time_offset_s = sigma;
  std::mt19937_64 rng(5);
  OffsetRun r;
  const double t0 = sc.trajectory->startTime();
  sim::runSimulation(sc, c, sim::trueNavState(*sc.trajectory, t0), rng, [&](EkfSlam&, sim::FrameRecord& rec) {
    r.final_offset = rec.estimate.t_d;
    r.final_sigma = rec.estimate.t_d_sigma;
    r.final_error = (rec.truth.p_n_b - rec.estimate.p_n_b).norm();
    if (rec.t - t0 < 10.0) r.offset_at_10s = rec.estimate.t_d;
  });
  return r;
}

}  // namespace

// A camera 40 ms late against the IMU, the filter started from 0 with 50 ms of doubt (the
// node's default): the offset is estimated through each feature's image velocity and ends within
// 2 ms of the truth, inside its own 3-sigma; the trajectory stays as good as with a known offset.
TEST(TimeOffset, ConvergesFromZeroToTheSimulatedOffset) {
  const OffsetRun known = runWithOffset(0.04, 0.04, 0.0);
  const OffsetRun estimated = runWithOffset(0.04, 0.0, 0.05);
  const OffsetRun ignored = runWithOffset(0.04, 0.0, 0.0);
  std::printf(
      "offset: after 10 s %.4f s, final %.4f +- %.4f s; final error: known %.3f m, estimated %.3f m, "
      "ignored %.3f m\n",
      estimated.offset_at_10s, estimated.final_offset, estimated.final_sigma, known.final_error, estimated.final_error,
      ignored.final_error);
  EXPECT_NEAR(estimated.final_offset, 0.04, 0.002);
  EXPECT_LT(std::abs(estimated.final_offset - 0.04), 3.0 * estimated.final_sigma + 1e-4);
  EXPECT_LT(estimated.final_error, 2.0 * known.final_error + 0.05);
  EXPECT_NEAR(known.final_offset, 0.04, 1e-12);  // sigma 0: fixed
}

// The other sign, and a start from a wrong value on the far side.
TEST(TimeOffset, ConvergesForANegativeOffset) {
  const OffsetRun r = runWithOffset(-0.047, 0.0, 0.05);
  std::printf("offset -0.047: final %.4f +- %.4f s, final error %.3f m\n", r.final_offset, r.final_sigma,
              r.final_error);
  EXPECT_NEAR(r.final_offset, -0.047, 0.002);
}
