// The dynamic initializer's cost: one alignment attempt (DynamicInitializer::tryInitialize) on a
// 1 s window of the built-in walk, 20 images of up to 80 tracked features with 1 px noise and an
// exact IMU at 200 Hz. The node makes one attempt per image until the filter starts, so this is
// the time an image waits while the rig is not yet initialized.
#include <benchmark/benchmark.h>

#include <random>

#include "vi_ekf_slam/core/dynamic_init/dynamic_initializer.h"
#include "vi_ekf_slam/core/imu_propagation.h"
#include "vi_ekf_slam/sim/camera_simulator.h"
#include "vi_ekf_slam/sim/scenarios.h"

using namespace vi_ekf_slam;

namespace {

void BM_DynamicInitAttempt(::benchmark::State& st) {
  const sim::Scenario sc = sim::hallwayScenario(sim::HallwayParams(), 1.0, 5);
  DynamicInitializer init(DynamicInitParams(), sc.camera, sc.T_b_c);
  sim::CameraSimParams cp;
  cp.pixel_noise_px = 1.0;
  cp.max_features = 80;
  sim::TrackingCamera camera(sc.world, sc.camera, sc.T_b_c, cp);
  std::mt19937_64 rng(3);
  const double t0 = 5.0, t1 = 6.0;
  for (double t = t0 - 0.2; t <= t1 + 0.2; t += 0.005) {  // the time offset search's margins
    const sim::TrajectorySample s = sc.trajectory->sample(t);
    init.addImu({t, s.w_b, s.q_n_b.conjugate() * (s.a_n_b - gravityInNav(9.81))});
  }
  for (int k = 0; k <= 20; ++k) {
    const double t = t0 + 0.05 * k;
    CameraFrame f = camera.observe(sc.trajectory->sample(t), &rng);
    f.timestamp = t;
    init.addFrame(f);
  }
  std::string why;
  if (!init.tryInitialize(&why)) st.SkipWithError(("the window did not initialize: " + why).c_str());
  for (auto _ : st) benchmark::DoNotOptimize(init.tryInitialize(nullptr));
}
BENCHMARK(BM_DynamicInitAttempt)->Unit(::benchmark::kMillisecond);

}  // namespace
