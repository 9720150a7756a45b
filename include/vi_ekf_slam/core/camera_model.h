// Pinhole camera with radial-tangential (ROS "plumb_bob", OpenCV's default model) or
// equidistant (Kannala-Brandt, ROS "equidistant", cv::fisheye) distortion, with the analytic
// projection Jacobian J_pi of the paper's eq. (30).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace vi_ekf_slam {

enum class DistortionModel { kNone, kRadTan, kEquidistant };

struct CameraIntrinsics {
  int width = 0;                                  ///< [px]
  int height = 0;                                 ///< [px]
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;  ///< [px]
  DistortionModel model = DistortionModel::kNone;
  /// kRadTan: k1 k2 p1 p2 [k3]; kEquidistant: k1 k2 k3 k4.
  std::vector<double> distortion;
  /// Empty when usable, otherwise what is wrong (zero focal length, bad size, NaN, ...).
  std::string validate() const;
};

/// A distortion-free camera of width x height px with focal length f_px [px] and its principal
/// point at the image's centre.
CameraIntrinsics pinholeIntrinsics(int width, int height, double f_px);

class CameraModel {
 public:
  CameraModel() = default;
  explicit CameraModel(const CameraIntrinsics& intrinsics);

  const CameraIntrinsics& intrinsics() const { return intr_; }
  int width() const { return intr_.width; }
  int height() const { return intr_.height; }

  /// Normalized undistorted image coordinates (x/z, y/z) -> distorted normalized coordinates.
  Eigen::Vector2d distort(const Eigen::Vector2d& xn, Eigen::Matrix2d* J = nullptr) const;
  /// Normalized undistorted coordinates -> pixel; J = d(uv)/d(xn).
  Eigen::Vector2d normalizedToPixel(const Eigen::Vector2d& xn, Eigen::Matrix2d* J = nullptr) const;
  /// Pixel -> normalized undistorted coordinates; J = d(xn)/d(uv). False if it does not converge.
  bool pixelToNormalized(const Eigen::Vector2d& uv, Eigen::Vector2d* xn, Eigen::Matrix2d* J = nullptr) const;
  /// Projects a point given in the camera frame; J = d(uv)/d(p_c) (2x3). False if the point
  /// is not in front of the camera.
  bool project(const Eigen::Vector3d& p_c, Eigen::Vector2d* uv, Eigen::Matrix<double, 2, 3>* J = nullptr) const;
  bool inImage(const Eigen::Vector2d& uv, double border_px = 0.0) const;

 private:
  CameraIntrinsics intr_;
  double k_[5] = {0, 0, 0, 0, 0};
};

}  // namespace vi_ekf_slam
