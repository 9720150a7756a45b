// Telling an image's structure from its sensor noise. In the dark a camera's gain turns the image
// into noise, and a corner detector that ranks corners against the best one of the image finds as
// many corners in pure noise as in a lit scene; tracked, they are measurements of nothing. A corner
// is kept only where the image holds more gradient than its own noise would give.
#pragma once

#include <opencv2/core.hpp>

namespace vi_ekf_slam {

/// The standard deviation of the image's noise [grey levels], by Immerkaer's Laplacian-difference
/// filter (the mask [1 -2 1; -2 4 -2; 1 -2 1] cancels smooth shading; on i.i.d. noise its output
/// has a standard deviation of 6 sigma), read by the median of its magnitude so that the edges of
/// the scene (a minority of the pixels) do not count as noise. At least kImageNoiseFloor.
double imageNoiseSigma(const cv::Mat& mono8);
/// The least noise an 8-bit image has [grey levels]: its quantization (1/sqrt(12)) and some; a
/// rendered image's is zero, which would make every gradient infinitely significant.
constexpr double kImageNoiseFloor = 0.5;

/// The signal-to-noise ratio of corners in one image. It is read on the image's first pyramid
/// level (cv::pyrDown, in floating point): a scene's structure survives the halving while the
/// noise's standard deviation drops to 70/256 of the image's (the sum of the squared weights of
/// pyrDown's 5 x 5 kernel), so faint real corners (dim light) stand out from noise far better
/// than at full size, where the noise's own gradients are as strong.
class CornerSignal {
 public:
  explicit CornerSignal(const cv::Mat& mono8);
  /// The image's noise (imageNoiseSigma) [grey levels].
  double noiseSigma() const { return sigma_; }
  /// The corner at `p` (full-size pixels) over a window_px x window_px window of the first level
  /// [ratio]: the smaller eigenvalue of the window's gradient matrix (central differences) over
  /// what the level's noise alone gives on average (n sigma^2 / 2). About 1 on noise alone; the
  /// largest over a whole 800 x 450 image of noise is about 3 with 15 px windows. Near the border
  /// the window is cut to the level.
  double snr(const cv::Point2f& p, int window_px) const;

 private:
  double sigma_;
  double level_sigma_;
  cv::Mat level_;  ///< CV_32F
};

}  // namespace vi_ekf_slam
