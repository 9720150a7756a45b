// Image renderer for the simulator (OpenCV, CPU): casts one ray per pixel through the lens model
// (so distortion is exact) against textured planar quads, with mip-mapped textures to avoid
// aliasing at distance, Gaussian sensor noise and optional motion blur.
#pragma once

#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "vi_ekf_slam/core/measurement_model.h"
#include "vi_ekf_slam/sim/hallway.h"
#include "vi_ekf_slam/sim/trajectory.h"

namespace vi_ekf_slam::sim {

struct RenderParams {
  double texel_m = 0.01;        ///< texture resolution [m]
  double noise_sigma = 2.0;     ///< per-pixel Gaussian intensity noise [gray levels]
  int motion_blur_samples = 1;  ///< > 1: average this many renders over the exposure
  double exposure_s = 0.008;    ///< exposure time for motion blur [s]
  std::uint64_t texture_seed = 1;
};

/// Procedural corridor texture for a quad (walls: panels, posters, door frames, baseboard;
/// floor: tiles; ceiling: panels and lights; all with speckle), values 0-255.
cv::Mat makeTexture(const Quad& quad, double texel_m, std::mt19937_64& rng);

class Renderer {
 public:
  Renderer(const std::vector<Quad>& quads, const CameraModel& camera, const CameraExtrinsics& T_b_c,
           const RenderParams& params);
  /// The mono8 image of the camera on the body at trajectory time t (with noise and blur).
  cv::Mat render(const Trajectory& trajectory, double t, std::mt19937_64& rng) const;
  /// Noise-free, blur-free render for a body pose (CV_32F, 0-255).
  cv::Mat renderPose(const Vec3& p_n_b, const Quat& q_n_b) const;

 private:
  struct Surface {
    Quad quad;
    std::vector<cv::Mat> mips;  ///< CV_32F pyramids
  };
  std::vector<Surface> surfaces_;
  CameraModel camera_;
  CameraExtrinsics T_b_c_;
  RenderParams params_;
  cv::Mat rays_;  ///< CV_32FC3 unit rays in the camera frame, one per pixel
};

}  // namespace vi_ekf_slam::sim
