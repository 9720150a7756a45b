// Renders a simulated walk into a rosbag with the topics of a real rig (see bag_io.h):
// /imu (200 Hz), /camera/image_raw (mono8, 28 Hz), /camera/camera_info, /tf_static,
// /ground_truth/pose, and /sim/world (the rendered quads, for evaluations).
//
//   vi_ekf_slam_make_bag --out FILE [--trajectory builtin|TUM_FILE] [--duration S] [--standing S]
//                        [--seed N] [--blur SAMPLES]
// The built-in walk stands still for --standing seconds (2) first, so the filter can initialize
// from a static interval, and walks the paper's hallway (turn at standing + 23 s).
#include <chrono>
#include <cstdio>
#include <iostream>

#include "cli.h"
#include "vi_ekf_slam/core/frames.h"
#include "vi_ekf_slam/ros/bag_io.h"
#include "vi_ekf_slam/sim/renderer.h"
#include "vi_ekf_slam/sim/scenarios.h"

using namespace vi_ekf_slam;

int main(int argc, char** argv) {
  std::string out, trajectory = "builtin";
  double duration = 35.0, standing = 2.0;
  int seed = 1, blur = 1;
  const std::string usage =
      "vi_ekf_slam_make_bag --out FILE [--trajectory builtin|TUM_FILE] [--duration S] [--standing S] [--seed N] "
      "[--blur SAMPLES]";
  cli::po::options_description opts("options");
  opts.add_options()("out", cli::po::value(&out)->required(), "the bag to write")(
      "trajectory", cli::po::value(&trajectory)->default_value(trajectory), "builtin, or a TUM file (z up)")(
      "duration", cli::po::value(&duration)->default_value(duration), "walk after the stand [s]")(
      "standing", cli::po::value(&standing)->default_value(standing), "built-in walk: stand still first [s]")(
      "seed", cli::po::value(&seed)->default_value(seed), "random seed")(
      "blur", cli::po::value(&blur)->default_value(blur), "motion blur: renders averaged per image [count]");
  cli::parse(argc, argv, usage, "Renders a simulated walk into a rosbag with the topics of a real rig.", opts);
  if (!(duration > 0.0) || !(standing >= 0.0)) cli::fail(usage, "--duration must be > 0 and --standing >= 0");
  if (blur < 1) cli::fail(usage, "--blur must be >= 1");
  const auto tic = std::chrono::steady_clock::now();
  sim::Scenario sc;
  std::vector<sim::Quad> quads;
  double t_begin = 0.0;
  try {
    if (trajectory == "builtin") {
      sim::HallwayParams hp;
      hp.standing_s = standing;
      hp.duration_s = standing + duration;
      hp.turn_time_s = standing + 23.0;
      sc = sim::hallwayScenario(hp, 1.0, static_cast<std::uint64_t>(seed));
      quads = sim::hallwayGeometry(hp);
    } else {
      // A TUM trajectory in a textured room around it; it starts as recorded (hold the rig
      // still at the start of the file for a static initialization).
      sc = sim::tumScenario(trajectory, 15.0, static_cast<std::uint64_t>(seed));
      quads = sim::roomAroundTrajectory(*sc.trajectory, 3.0, 1.3, 1.5);
      t_begin = sc.trajectory->startTime();
    }
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  const double t_end = std::min(sc.trajectory->endTime(), t_begin + standing + duration);
  std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
  sc.imu.initial_accel_bias_sigma_mps2 = 0.03;
  sc.imu.initial_gyro_bias_sigma_radps = 0.002;
  const sim::ImuSequence imu = sim::simulateImu(*sc.trajectory, sc.imu, rng);
  sim::RenderParams rp;
  rp.motion_blur_samples = blur;
  rp.texture_seed = static_cast<std::uint64_t>(seed);
  const sim::Renderer renderer(quads, sc.camera, sc.T_b_c, rp);
  // Stamps look like a real recording: an epoch plus the trajectory time.
  const double epoch = trajectory == "builtin" ? 1.6e9 : 0.0;
  glue::RigBagWriter bag(out, glue::RigTopics(), sc.camera, sc.T_b_c, sc.imu.noise, sc.imu.rate_hz,
                         ros::Time(epoch + t_begin));
  bag.text("/sim/world", epoch + t_begin, sim::serializeQuads(quads));
  size_t k = 0;
  int frames = 0;
  for (double t = t_begin; t <= t_end + 1e-9; t += 1.0 / sc.cam.rate_hz) {
    for (; k < imu.samples.size() && imu.samples[k].timestamp <= t + 1e-9; ++k) {
      ImuData d = imu.samples[k];
      if (d.timestamp < t_begin) continue;
      d.timestamp += epoch;
      bag.imu(d);
    }
    bag.image(epoch + t, renderer.render(*sc.trajectory, t, rng));
    const sim::TrajectorySample s = sc.trajectory->sample(t);
    Vec3 p_w;
    Quat q_w_b;
    navToZUpWorld(s.p_n_b, s.q_n_b, &p_w, &q_w_b);
    bag.groundTruth(epoch + t, p_w, q_w_b);
    ++frames;
  }
  for (; k < imu.samples.size() && imu.samples[k].timestamp <= t_end + 0.1; ++k) {
    ImuData d = imu.samples[k];
    d.timestamp += epoch;
    bag.imu(d);
  }
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - tic).count();
  std::printf("make_bag: %s: %.1f s of data, %d images, %zu IMU samples, rendered in %.1f s\n", out.c_str(),
              t_end - t_begin, frames, k, secs);
  return 0;
}
