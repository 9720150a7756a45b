#include "vi_ekf_slam/sim/recorded_imu.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "vi_ekf_slam/io/datasets.h"
#include "vi_ekf_slam/sim/bspline_trajectory.h"
#include "vi_ekf_slam/sim/hallway.h"
#include "vi_ekf_slam/sim/scenarios.h"

namespace vi_ekf_slam::sim {

namespace fs = std::filesystem;

namespace {

bool isAslGroundTruth(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty()) return line.find(',') != std::string::npos;
  }
  return false;
}

/// Linear interpolation of the ground-truth biases at time t (clamped at the ends).
void biasesAt(const std::vector<io::AslState>& gt, double t, Vec3* b_a, Vec3* b_g) {
  auto it = std::lower_bound(gt.begin(), gt.end(), t, [](const io::AslState& s, double x) { return s.t < x; });
  if (it == gt.begin() || it == gt.end()) {
    const io::AslState& s = it == gt.end() ? gt.back() : gt.front();
    *b_a = s.b_a;
    *b_g = s.b_g;
    return;
  }
  const io::AslState& a = *(it - 1);
  const io::AslState& b = *it;
  const double w = (t - a.t) / std::max(1e-12, b.t - a.t);
  *b_a = (1.0 - w) * a.b_a + w * b.b_a;
  *b_g = (1.0 - w) * a.b_g + w * b.b_g;
}

}  // namespace

Scenario recordedImuScenario(const std::string& trajectory_path, const std::string& imu_csv, double per_metre,
                             std::uint64_t world_seed) {
  Scenario sc;
  std::vector<io::AslState> gt;
  std::vector<io::StampedPose> poses;
  if (isAslGroundTruth(trajectory_path)) {
    gt = io::readAslGroundTruth(trajectory_path);
    poses = io::toStampedPoses(gt);
  } else {
    poses = io::readTum(trajectory_path);
  }
  if (poses.size() < 4 || poses.back().t - poses.front().t < 1.0) {
    throw std::runtime_error(trajectory_path + ": too short for a trajectory (needs 4 poses over 1 s)");
  }
  for (auto& p : poses) p = worldZUpToNav(p);
  auto traj = std::make_shared<BsplineTrajectory>(poses, 0.05);
  sc.trajectory = traj;

  const std::vector<ImuData> all = io::readAslImu(imu_csv);
  auto seq = std::make_shared<ImuSequence>();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const ImuData& d : all) {
    if (d.timestamp < traj->startTime() || d.timestamp > traj->endTime()) continue;
    seq->samples.push_back(d);
    Vec3 b_a = Vec3::Constant(nan), b_g = Vec3::Constant(nan);
    if (!gt.empty()) biasesAt(gt, d.timestamp, &b_a, &b_g);
    seq->true_accel_bias.push_back(b_a);
    seq->true_gyro_bias.push_back(b_g);
  }
  if (seq->samples.size() < 2) {
    throw std::runtime_error(imu_csv + ": no IMU samples inside the ground truth's time span [" +
                             std::to_string(traj->startTime()) + ", " + std::to_string(traj->endTime()) +
                             "] s; are both from the same recording?");
  }
  sc.recorded_imu = seq;
  const double span = seq->samples.back().timestamp - seq->samples.front().timestamp;
  sc.imu.rate_hz = (seq->samples.size() - 1) / std::max(1e-9, span);

  const fs::path imu_dir = fs::path(imu_csv).parent_path();
  const fs::path imu_yaml = imu_dir / "sensor.yaml";
  sc.imu.noise = fs::exists(imu_yaml) ? io::readAslImuNoise(imu_yaml.string()) : paperImuNoise();
  const fs::path cam_yaml = imu_dir.parent_path() / "cam0" / "sensor.yaml";
  if (fs::exists(cam_yaml)) {
    const io::AslCamera cam = io::readAslCamera(cam_yaml.string());
    sc.camera = CameraModel(cam.intrinsics);
    sc.T_b_c = cam.T_b_c;
    if (cam.rate_hz > 0.0) sc.cam.rate_hz = cam.rate_hz;
  } else {
    sc.camera = paperCamera();
    sc.T_b_c = forwardLookingExtrinsics(*traj);
  }
  std::mt19937_64 rng(world_seed);
  sc.world = landmarksAroundTrajectory(*traj, per_metre, 1.0, 10.0, rng);
  return sc;
}

}  // namespace vi_ekf_slam::sim
