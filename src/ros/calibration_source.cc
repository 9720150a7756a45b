#include "vi_ekf_slam/ros/calibration_source.h"

#include <camera_calibration_parsers/parse.h>
#include <ros/console.h>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <tf2/exceptions.h>

#include "vi_ekf_slam/ros/conversions.h"

namespace vi_ekf_slam::glue {

namespace {

/// Equal to the digits a calibration file keeps (a driver's float32 camera_info included).
bool sameIntrinsics(const CameraIntrinsics& a, const CameraIntrinsics& b) {
  auto near = [](double x, double y) { return std::abs(x - y) <= 1e-6 * std::max(1.0, std::abs(x)); };
  if (a.width != b.width || a.height != b.height || a.model != b.model) return false;
  if (!near(a.fx, b.fx) || !near(a.fy, b.fy) || !near(a.cx, b.cx) || !near(a.cy, b.cy)) return false;
  const size_t n = std::max(a.distortion.size(), b.distortion.size());
  for (size_t i = 0; i < n; ++i) {
    const double da = i < a.distortion.size() ? a.distortion[i] : 0.0;
    const double db = i < b.distortion.size() ? b.distortion[i] : 0.0;
    if (!near(da, db)) return false;
  }
  return true;
}

std::string describe(const CameraIntrinsics& k) {
  std::ostringstream s;
  s << k.width << "x" << k.height << " fx " << k.fx << " fy " << k.fy << " cx " << k.cx << " cy " << k.cy;
  return s.str();
}

}  // namespace

std::string intrinsicsFromOptions(const NodeOptions& o, std::optional<CameraIntrinsics>* out) {
  if (o.camera_intrinsics.empty()) return "";
  if (o.camera_intrinsics.size() != 4) return "camera_intrinsics takes fx fy cx cy";
  if (o.camera_resolution.size() != 2) return "camera_intrinsics needs camera_resolution: width height";
  CameraIntrinsics k;
  k.fx = o.camera_intrinsics[0];
  k.fy = o.camera_intrinsics[1];
  k.cx = o.camera_intrinsics[2];
  k.cy = o.camera_intrinsics[3];
  k.width = static_cast<int>(o.camera_resolution[0]);
  k.height = static_cast<int>(o.camera_resolution[1]);
  if (k.width != o.camera_resolution[0] || k.height != o.camera_resolution[1]) {
    return "camera_resolution takes whole pixels";
  }
  k.distortion = o.camera_distortion_coeffs;
  const bool zero = std::all_of(k.distortion.begin(), k.distortion.end(), [](double d) { return d == 0.0; });
  if (o.camera_distortion_model == "equidistant") {
    if (k.distortion.size() != 4) return "camera_distortion_coeffs: equidistant takes k1 k2 k3 k4";
    k.model = DistortionModel::kEquidistant;
  } else if (k.distortion.empty() || zero) {
    k.model = DistortionModel::kNone;
    k.distortion.clear();
  } else {
    if (k.distortion.size() != 4 && k.distortion.size() != 5) {
      return "camera_distortion_coeffs: radtan takes k1 k2 p1 p2 [k3]";
    }
    k.model = DistortionModel::kRadTan;
  }
  const std::string bad = k.validate();
  if (!bad.empty()) return "camera_intrinsics: " + bad;
  *out = k;
  return "";
}

CalibrationSource::CalibrationSource(const NodeOptions& o) : file_wins_(o.calibration_source == "file") {
  if (o.extrinsic_source == "parameters") {
    const auto& v = o.T_b_c;
    CameraExtrinsics T;
    T.p_b_c = Vec3(v[0], v[1], v[2]);
    T.R_b_c = Quat(v[6], v[3], v[4], v[5]).normalized().toRotationMatrix();
    extrinsics_ = T;
  }
  const std::string bad = intrinsicsFromOptions(o, &intrinsics_);
  if (!bad.empty()) throw std::invalid_argument("vi_ekf_slam: " + bad);
  if (intrinsics_) intrinsics_from_ = o.kalibr_camchain.empty() ? "camera_intrinsics" : o.kalibr_camchain;
  if (!o.camera_calibration_file.empty()) {
    std::string name;
    sensor_msgs::CameraInfo info;
    CameraIntrinsics in;
    if (!camera_calibration_parsers::readCalibration(o.camera_calibration_file, name, info)) {
      throw std::invalid_argument("vi_ekf_slam: cannot read camera_calibration_file '" + o.camera_calibration_file +
                                  "'");
    }
    const std::string e = intrinsicsFromCameraInfo(info, &in);
    if (!e.empty()) throw std::invalid_argument("vi_ekf_slam: camera_calibration_file: " + e);
    intrinsics_ = in;
    intrinsics_from_ = o.camera_calibration_file;
  }
  if (intrinsics_) {
    ROS_INFO("vi_ekf_slam: camera %s from %s%s", describe(*intrinsics_).c_str(), intrinsics_from_.c_str(),
             file_wins_ ? "" : " until camera_info arrives (calibration_source camera_info)");
  }
}

CameraInfoUse CalibrationSource::cameraInfo(const sensor_msgs::CameraInfo& msg) {
  CameraInfoUse use;
  CameraIntrinsics in;
  use.error = intrinsicsFromCameraInfo(msg, &in);
  if (!use.error.empty()) return use;
  if (intrinsics_ && sameIntrinsics(in, *intrinsics_)) return use;
  if (file_wins_) {
    use.ignored = true;
    if (!said_ignored_) {
      use.ignored_once = "camera_info (" + describe(in) + ") differs from " + intrinsics_from_ + " (" +
                         describe(*intrinsics_) + "): ignored (calibration_source file)";
      said_ignored_ = true;
    }
    return use;
  }
  use.changed = true;
  intrinsics_ = in;
  intrinsics_from_ = "camera_info";
  ROS_INFO("vi_ekf_slam: camera %s from camera_info", describe(in).c_str());
  return use;
}

std::string CalibrationSource::summary() const {
  if (!intrinsics_) return "no intrinsics yet";
  return describe(*intrinsics_) + " from " + intrinsics_from_ + (said_ignored_ ? "; camera_info differs, ignored" : "");
}

std::string CalibrationSource::ready(const std::string& image_frame, const std::string& imu_frame,
                                     const tf2::BufferCore* tf) {
  if (!intrinsics_) return "no valid camera_info (and no intrinsics from a file) yet";
  if (extrinsics_) return "";
  if (image_frame.empty()) return "image has no frame_id: cannot look up the camera-IMU transform";
  if (imu_frame.empty())
    return "waiting for IMU messages (their frame_id is the IMU frame of the camera-IMU transform)";
  if (image_frame == imu_frame) {
    extrinsics_ = CameraExtrinsics();
    return "";
  }
  if (!tf) return "no TF available for the camera-IMU transform";
  try {
    extrinsics_ = extrinsicsFromTransform(tf->lookupTransform(imu_frame, image_frame, ros::Time(0)).transform);
    ROS_INFO("vi_ekf_slam: camera-IMU transform %s <- %s from TF", imu_frame.c_str(), image_frame.c_str());
    return "";
  } catch (const tf2::TransformException& e) {
    return "waiting for TF " + imu_frame + " <- " + image_frame + ": " + e.what();
  }
}

}  // namespace vi_ekf_slam::glue
