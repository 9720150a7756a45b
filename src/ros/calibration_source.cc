#include "vi_ekf_slam/ros/calibration_source.h"

#include <camera_calibration_parsers/parse.h>
#include <ros/console.h>
#include <stdexcept>
#include <tf2/exceptions.h>

#include "vi_ekf_slam/ros/conversions.h"

namespace vi_ekf_slam::glue {

CalibrationSource::CalibrationSource(const NodeOptions& o) {
  if (o.extrinsic_source == "parameters") {
    const auto& v = o.T_b_c;
    CameraExtrinsics T;
    T.p_b_c = Vec3(v[0], v[1], v[2]);
    T.R_b_c = Quat(v[6], v[3], v[4], v[5]).normalized().toRotationMatrix();
    extrinsics_ = T;
  }
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
    ROS_INFO("vi_ekf_slam: camera calibration from %s (%dx%d), used until camera_info arrives",
             o.camera_calibration_file.c_str(), in.width, in.height);
  }
}

std::string CalibrationSource::cameraInfo(const sensor_msgs::CameraInfo& msg, bool* changed) {
  *changed = false;
  CameraIntrinsics in;
  const std::string err = intrinsicsFromCameraInfo(msg, &in);
  if (!err.empty()) return err;
  const auto& k = intrinsics_;
  *changed = !k || in.fx != k->fx || in.fy != k->fy || in.cx != k->cx || in.cy != k->cy || in.width != k->width ||
             in.height != k->height || in.distortion != k->distortion || in.model != k->model;
  if (*changed) {
    intrinsics_ = in;
    ROS_INFO("vi_ekf_slam: camera %dx%d fx=%.1f fy=%.1f from camera_info", in.width, in.height, in.fx, in.fy);
  }
  return "";
}

std::string CalibrationSource::ready(const std::string& image_frame, const std::string& imu_frame,
                                     const tf2::BufferCore* tf) {
  if (!intrinsics_) return "no valid camera_info (and no camera_calibration_file) yet";
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
