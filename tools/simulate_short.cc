// A short simulated run through the core for each mechanization: prints the estimated and the
// true final pose. Used by `make demo` until the full replay exists.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "cli.h"
#include "vi_ekf_slam/sim/scenarios.h"

using namespace vi_ekf_slam;

int main(int argc, char** argv) {
  double duration = 30.0;
  unsigned seed = 1u;
  const std::string usage = "vi_ekf_slam_simulate_short [DURATION_S (30)] [SEED (1)]";
  cli::po::options_description opts("options");
  opts.add_options()("duration", cli::po::value(&duration)->default_value(duration), "walk duration [s]")(
      "seed", cli::po::value(&seed)->default_value(seed), "random seed");
  cli::po::positional_options_description pos;
  pos.add("duration", 1).add("seed", 1);
  cli::parse(argc, argv, usage,
             "A short simulated walk on a circle through the core for each mechanization: the estimated and the true "
             "final pose.",
             opts, pos);
  if (!(duration >= 1.0)) cli::fail(usage, "the duration must be >= 1 s");
  const sim::Scenario sc = sim::circleScenario(duration, /*noise=*/true, seed);
  std::printf("Simulated walk on a %.0f s circle (r = 6 m), IMU 200 Hz, camera 28 Hz, 1 px noise, seed %u\n\n",
              duration, seed);
  std::printf("%-28s %9s %9s %9s | %9s %9s %9s | %8s %8s %6s %6s\n", "mechanization", "est x", "est y", "est z",
              "true x", "true y", "true z", "pos err", "yaw err", "lmks", "comp");
  for (auto m :
       {Mechanization::kWorldCentric, Mechanization::kSensorCentric, Mechanization::kSensorCentricComposition}) {
    EkfSlamConfig cfg;
    cfg.mechanization = m;
    cfg.imu_noise = sc.imu.noise;
    std::mt19937_64 rng(seed);
    int compositions = 0;
    const sim::SimRun run = sim::runSimulation(sc, cfg, sim::trueNavState(*sc.trajectory, 0.0), rng,
                                               [&](EkfSlam& f, sim::FrameRecord&) { compositions = f.compositions(); });
    const auto& last = run.frames.back();
    const Vec3 e = last.estimate.p_n_b, t = last.truth.p_n_b;
    const double yaw_err = rotationError(last.estimate.q_n_b, last.truth.q_n_b).z() * 180.0 / M_PI;
    std::printf("%-28s %9.3f %9.3f %9.3f | %9.3f %9.3f %9.3f | %7.3fm %7.2fd %6d %6d\n", toString(m).c_str(), e.x(),
                e.y(), e.z(), t.x(), t.y(), t.z(), (e - t).norm(), yaw_err, last.landmarks_in_state, compositions);
  }
  return 0;
}
