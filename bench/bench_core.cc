// Core benchmarks: cost of each filter operation against the map size N. Every
// family runs at N = 25, 50, 100, 200, 400; bench/summarize.py fits the growth exponent.
#include <benchmark/benchmark.h>

#include "bench_fixtures.h"
#include "vi_ekf_slam/platform/allocator_tuning.h"
#include "vi_ekf_slam/core/ekf_slam.h"
#include "vi_ekf_slam/core/frame_change.h"
#include "vi_ekf_slam/core/imu_propagation.h"

using namespace vi_ekf_slam;
using vi_ekf_slam::bench::MapFixture;

namespace {

// As in the node and the tools (platform/allocator_tuning.h): large buffers stay in the heap.
const bool kAllocatorTuned = tuneAllocatorForLargeBuffers();

constexpr Mechanization kSc = Mechanization::kSensorCentricComposition;
const Vec3 kGravity = gravityInNav(9.81);
const Vec3 kWm(0.01, -0.02, 0.3), kAm(0.2, 0.1, -9.7);

void mapSizes(::benchmark::internal::Benchmark* b) {
  for (int n : {25, 50, 100, 200, 400}) b->Arg(n);
  b->Unit(::benchmark::kMicrosecond);
}

// One IMU sample: strapdown, Phi, Qd, motion covariance; the cross-covariance product is
// accumulated (lazy), so the cost must not depend on N.
void BM_ImuStep(::benchmark::State& st) {
  MapFixture f(kSc, static_cast<int>(st.range(0)));
  for (auto _ : st) {
    propagateState(f.state, kWm, kAm, 0.005, ImuNoiseParams(), kGravity);
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_ImuStep)->Apply(mapSizes);

// One camera interval at 200 Hz IMU / 28 Hz camera: 7 samples, then the accumulated Phi applied
// once to the motion-landmark cross-covariance (what reading the covariance for an update does).
void BM_ImuIntervalWithFlush(::benchmark::State& st) {
  MapFixture f(kSc, static_cast<int>(st.range(0)));
  for (auto _ : st) {
    for (int k = 0; k < 7; ++k) propagateState(f.state, kWm, kAm, 0.005, ImuNoiseParams(), kGravity);
    benchmark::DoNotOptimize(f.state.covariance().data());
  }
}
BENCHMARK(BM_ImuIntervalWithFlush)->Apply(mapSizes);

// The odom_imu latency: the pose published at an IMU sample is the last update's state propagated
// (motion state alone) through the samples since; the worst case is the end of a camera interval
// (7 samples at 200 Hz / 28 Hz). Independent of the map size by construction.
void BM_ImuRatePose(::benchmark::State& st) {
  EkfSlamConfig cfg;
  EkfSlam filter(cfg, sim::paperCamera(), CameraExtrinsics());
  filter.initialize(NavState());
  for (int k = 0; k <= 7; ++k) filter.addImu({0.005 * k, kWm, kAm});
  for (auto _ : st) benchmark::DoNotOptimize(filter.predictedNavState());
}
BENCHMARK(BM_ImuRatePose)->Unit(::benchmark::kMicrosecond);

// One image update with 30 observations (stacked, gated, Joseph form), on a fresh copy.
void BM_Update30(::benchmark::State& st) {
  const MapFixture f(kSc, static_cast<int>(st.range(0)));
  UpdateParams up;
  for (auto _ : st) {
    st.PauseTiming();
    FilterState s = f.state;
    s.covariance();
    st.ResumeTiming();
    const UpdateResult r = ekfUpdate(s, f.observations, f.camera, f.T_b_c, up);
    benchmark::DoNotOptimize(r.accepted);
  }
}
BENCHMARK(BM_Update30)->Apply(mapSizes);

// One new landmark (inverse depth) appended with its cross-covariance.
void BM_LandmarkInit(::benchmark::State& st) {
  const MapFixture f(kSc, static_cast<int>(st.range(0)));
  const FeatureObservation obs{1000000, Eigen::Vector2d(300.0, 200.0)};
  for (auto _ : st) {
    st.PauseTiming();
    FilterState s = f.state;
    s.covariance();
    st.ResumeTiming();
    initializeLandmarkInverseDepth(s, obs, f.camera, f.T_b_c, InverseDepthParams());
    benchmark::DoNotOptimize(s.mutableCovariance().data());
  }
}
BENCHMARK(BM_LandmarkInit)->Apply(mapSizes);

// The composition step (eq. 31-33) with its structured O(n^2) covariance transform.
void BM_Composition(::benchmark::State& st) {
  MapFixture f(kSc, static_cast<int>(st.range(0)));
  for (auto _ : st) {
    compose(f.state);
    benchmark::DoNotOptimize(f.state.mutableCovariance().data());
  }
}
BENCHMARK(BM_Composition)->Apply(mapSizes);

// A mechanization switch, alternating world-centric <-> sensor-centric (state, map, covariance).
void BM_MechanizationSwitch(::benchmark::State& st) {
  MapFixture f(kSc, static_cast<int>(st.range(0)));
  bool to_world = true;
  for (auto _ : st) {
    switchMechanization(f.state, to_world ? Mechanization::kWorldCentric : kSc);
    to_world = !to_world;
    benchmark::DoNotOptimize(f.state.mutableCovariance().data());
  }
}
BENCHMARK(BM_MechanizationSwitch)->Apply(mapSizes);

}  // namespace
