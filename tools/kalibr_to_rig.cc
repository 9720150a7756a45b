// Writes a rig file (node parameters on top of config/vi_ekf_slam.yaml) from Kalibr's
// camchain-imucam.yaml and imu.yaml, and checks that the node accepts it.
//
//   vi_ekf_slam_kalibr_to_rig --camchain camchain-imucam.yaml [--imu imu.yaml] [--out rig.yaml]
#include <fstream>
#include <iostream>

#include "cli.h"
#include "vi_ekf_slam/ros/kalibr_import.h"
#include "vi_ekf_slam/ros/params.h"

using namespace vi_ekf_slam;

int main(int argc, char** argv) {
  std::string camchain, imu, out;
  const std::string usage = "vi_ekf_slam_kalibr_to_rig --camchain FILE [--imu FILE] [--out rig.yaml]";
  cli::po::options_description opts("options");
  opts.add_options()("camchain", cli::po::value(&camchain), "Kalibr's camchain-imucam.yaml (cam0 is used)")(
      "imu", cli::po::value(&imu), "Kalibr's imu.yaml (noise densities and random walks)")(
      "out", cli::po::value(&out), "the rig file to write (default: print it)");
  cli::parse(argc, argv, usage,
             "Converts a Kalibr calibration into a rig file: T_b_c (the inverse of T_cam_imu), the intrinsics, "
             "distortion, resolution, timeshift_cam_imu, the line delay, the IMU noise. The node reads the same files "
             "directly through its parameters kalibr_camchain and kalibr_imu.",
             opts);
  if (camchain.empty() && imu.empty()) cli::fail(usage, "give --camchain, --imu or both");
  try {
    const glue::KalibrImport k = glue::importKalibr(camchain, imu);
    const std::string text = glue::kalibrRigFile(k, camchain, imu);
    // The node must accept what is written: load it as it would.
    glue::YamlParams rig;
    for (const auto& [name, value] : k.params) rig.set(name, value);
    glue::NodeParams params;
    const std::string err = glue::loadParams(rig, &params);
    if (!err.empty()) throw std::runtime_error("the node would refuse these values:\n" + err);
    if (out.empty()) {
      std::cout << text;
    } else {
      std::ofstream(out) << text;
      std::cerr << "wrote " << out << " (" << k.params.size() << " parameters)\n";
    }
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
