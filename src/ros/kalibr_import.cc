#include "vi_ekf_slam/ros/kalibr_import.h"

#include <yaml-cpp/yaml.h>
#include <Eigen/Geometry>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "vi_ekf_slam/ros/param_table.h"

namespace vi_ekf_slam::glue {
namespace {

YAML::Node loadFile(const std::string& path) {
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error("cannot read Kalibr file '" + path + "': " + e.what());
  }
}

/// A required entry of a Kalibr section, as T.
template <typename T>
T need(const YAML::Node& section, const std::string& key, const std::string& where) {
  if (!section[key]) throw std::runtime_error(where + ": no '" + key + "'");
  try {
    return section[key].as<T>();
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(where + ": '" + key + "' cannot be read: " + e.what());
  }
}

std::string yaml(double v) { return toYaml(ParamValue(v)); }
std::string yaml(const std::vector<double>& v) { return toYaml(ParamValue(v)); }

/// T_b_c = T_cam_imu^-1 as x y z qx qy qz qw, after checking that T_cam_imu is rigid.
std::vector<double> cameraInImu(const std::vector<std::vector<double>>& T, const std::string& where) {
  if (T.size() != 4 || T[0].size() != 4 || T[1].size() != 4 || T[2].size() != 4) {
    throw std::runtime_error(where + ": T_cam_imu is not a 4x4 matrix");
  }
  Eigen::Matrix3d R_c_i;
  Eigen::Vector3d p_c_i;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R_c_i(r, c) = T[r][c];
    p_c_i(r) = T[r][3];
  }
  // Kalibr writes 8 significant digits: a rotation is orthonormal to about 1e-7.
  if (!R_c_i.allFinite() || !p_c_i.allFinite() ||
      (R_c_i.transpose() * R_c_i - Eigen::Matrix3d::Identity()).norm() > 1e-4 || R_c_i.determinant() < 0.0) {
    throw std::runtime_error(where + ": T_cam_imu is not a rigid transform (its rotation is not orthonormal)");
  }
  const Eigen::Quaterniond q_b_c = Eigen::Quaterniond(R_c_i.transpose()).normalized();
  const Eigen::Vector3d p_b_c = -(q_b_c * p_c_i);
  return {p_b_c.x(), p_b_c.y(), p_b_c.z(), q_b_c.x(), q_b_c.y(), q_b_c.z(), q_b_c.w()};
}

void importCamchain(const std::string& path, KalibrImport* k) {
  const YAML::Node root = loadFile(path);
  const std::string where = path + ": cam0";
  const YAML::Node cam = root["cam0"];
  if (!cam || !cam.IsMap()) throw std::runtime_error(path + ": no cam0 (only the first camera is used)");
  const auto model = need<std::string>(cam, "camera_model", where);
  if (model != "pinhole") {
    throw std::runtime_error(where + ": camera_model '" + model +
                             "' (only pinhole: omni, ds and eucm are not supported)");
  }
  auto distortion = need<std::string>(cam, "distortion_model", where);
  const auto coeffs = need<std::vector<double>>(cam, "distortion_coeffs", where);
  if (distortion == "equi") distortion = "equidistant";  // older Kalibr spelling
  if (distortion == "none") distortion = "radtan";       // radtan with zero coefficients
  if (distortion != "radtan" && distortion != "equidistant") {
    throw std::runtime_error(where + ": distortion_model '" + distortion + "' (radtan, equidistant or none)");
  }
  const auto intrinsics = need<std::vector<double>>(cam, "intrinsics", where);
  const auto resolution = need<std::vector<double>>(cam, "resolution", where);
  if (intrinsics.size() != 4) throw std::runtime_error(where + ": pinhole intrinsics are [fu, fv, pu, pv]");
  if (resolution.size() != 2) throw std::runtime_error(where + ": resolution is [width, height]");
  const auto T = need<std::vector<std::vector<double>>>(cam, "T_cam_imu", where);
  k->params.emplace_back("camera_intrinsics", yaml(intrinsics));
  k->params.emplace_back("camera_resolution", yaml(resolution));
  k->params.emplace_back("camera_distortion_model", distortion);
  k->params.emplace_back("camera_distortion_coeffs", yaml(coeffs));
  k->params.emplace_back("extrinsic_source", "parameters");
  k->params.emplace_back("T_b_c", yaml(cameraInImu(T, where)));
  // Kalibr: t_imu = t_cam + timeshift_cam_imu, the convention of camera_time_offset_s.
  if (cam["timeshift_cam_imu"])
    k->params.emplace_back("camera_time_offset_s", yaml(need<double>(cam, "timeshift_cam_imu", where)));
  if (cam["line_delay"]) {
    // A rolling-shutter calibration: the delay between rows; first to last row over the image.
    const double readout = need<double>(cam, "line_delay", where) * (resolution[1] - 1.0);
    k->params.emplace_back("camera_readout_time_s", yaml(readout));
  } else {
    k->notes.push_back("no line_delay in " + path +
                       ": a global-shutter calibration (set camera_readout_time_s for a rolling shutter)");
  }
  if (cam["rostopic"]) k->image_topic = need<std::string>(cam, "rostopic", where);
}

void importImu(const std::string& path, KalibrImport* k) {
  const YAML::Node root = loadFile(path);
  // imu.yaml as kalibr_calibrate_imu_camera writes it (imu0: ...) or as its input (top level).
  const YAML::Node imu = root["imu0"] ? root["imu0"] : root;
  const std::string where = path + (root["imu0"] ? ": imu0" : "");
  k->params.emplace_back("accel_noise_density", yaml(need<double>(imu, "accelerometer_noise_density", where)));
  k->params.emplace_back("gyro_noise_density", yaml(need<double>(imu, "gyroscope_noise_density", where)));
  k->params.emplace_back("accel_random_walk", yaml(need<double>(imu, "accelerometer_random_walk", where)));
  k->params.emplace_back("gyro_random_walk", yaml(need<double>(imu, "gyroscope_random_walk", where)));
  if (imu["rostopic"]) k->imu_topic = need<std::string>(imu, "rostopic", where);
  if (imu["update_rate"]) k->imu_rate_hz = need<double>(imu, "update_rate", where);
  if (imu["T_i_b"]) {
    const auto T = need<std::vector<std::vector<double>>>(imu, "T_i_b", where);
    for (size_t r = 0; r < T.size(); ++r) {
      for (size_t c = 0; c < T[r].size(); ++c) {
        if (std::abs(T[r][c] - (r == c ? 1.0 : 0.0)) > 1e-9) {
          throw std::runtime_error(where + ": T_i_b is not the identity (only the IMU frame itself is supported)");
        }
      }
    }
  }
}

}  // namespace

KalibrImport importKalibr(const std::string& camchain_path, const std::string& imu_path) {
  KalibrImport k;
  if (!camchain_path.empty()) importCamchain(camchain_path, &k);
  if (!imu_path.empty()) importImu(imu_path, &k);
  return k;
}

std::string kalibrRigFile(const KalibrImport& k, const std::string& camchain_path, const std::string& imu_path) {
  std::ostringstream f;
  f << "# Rig file written by vi_ekf_slam_kalibr_to_rig from Kalibr's calibration\n";
  if (!camchain_path.empty()) f << "#   camchain: " << camchain_path << "\n";
  if (!imu_path.empty()) f << "#   imu:      " << imu_path << "\n";
  f << "# Loaded on top of config/vi_ekf_slam.yaml (rig:=FILE, run_bag --rig FILE).\n";
  if (k.imu_rate_hz > 0.0) f << "# IMU rate in imu.yaml: " << k.imu_rate_hz << " Hz\n";
  for (const std::string& n : k.notes) f << "# " << n << "\n";
  f << "# Uncomment to use these intrinsics even when the driver publishes a different camera_info:\n"
    << "# calibration_source: file\n";
  // The topics Kalibr's calibration recording had: the rig's drivers publish there.
  if (!k.imu_topic.empty()) f << "imu_topic: " << k.imu_topic << "\n";
  if (!k.image_topic.empty()) f << "image_topic: " << k.image_topic << "\n";
  for (const auto& [name, value] : k.params) f << name << ": " << value << "\n";
  return f.str();
}

}  // namespace vi_ekf_slam::glue
