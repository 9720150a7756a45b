// The image's noise and its corners' signal (image_noise.h): the noise estimate is the sensor's on
// flat and on textured images, pure noise never makes a corner at the tracker's threshold, and a
// faint real corner under the same noise does.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "test_helpers.h"
#include "vi_ekf_slam/core/feature_tracker.h"
#include "vi_ekf_slam/core/image_noise.h"

namespace vi_ekf_slam {
namespace {

/// The threshold the parameter's description suggests (noise alone reaches about 3).
constexpr double kMinCornerSnr = 5.0;

/// `scene` times `light` plus Gaussian noise of `sigma` grey levels, saturated to 8 bits.
cv::Mat underNoise(const cv::Mat& scene, double light, double sigma, std::uint64_t seed) {
  cv::Mat noise(scene.size(), CV_32F), f, out;
  cv::RNG(seed).fill(noise, cv::RNG::NORMAL, 0.0, sigma);
  scene.convertTo(f, CV_32F, light);
  f += noise;
  f.convertTo(out, CV_8U);
  return out;
}

/// Large squares of 40 and 200 (away from the clipping): edges and corners on a minority of the pixels.
cv::Mat checkerboard(int width, int height, int square) {
  cv::Mat img(height, width, CV_8UC1);
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c) img.at<uchar>(r, c) = ((r / square + c / square) % 2) ? 200 : 40;
  return img;
}

TEST(ImageNoise, TheEstimateIsTheSensorsNoiseOnFlatAndTexturedImages) {
  const cv::Mat flat(450, 800, CV_8UC1, cv::Scalar(100));
  for (double sigma : {2.0, 5.0, 10.0}) {
    EXPECT_NEAR(imageNoiseSigma(underNoise(flat, 1.0, sigma, 1)), sigma, 0.1 * sigma) << sigma;
    // The scene's edges are a minority of the pixels: they do not count as noise.
    EXPECT_NEAR(imageNoiseSigma(underNoise(checkerboard(800, 450, 40), 1.0, sigma, 2)), sigma, 0.15 * sigma) << sigma;
  }
  // A noise-free (rendered) image: the floor, not zero.
  EXPECT_EQ(imageNoiseSigma(flat), kImageNoiseFloor);
}

TEST(ImageNoise, PureNoiseNeverReachesTheTrackersThreshold) {
  const double threshold = kMinCornerSnr;
  const int window = TrackerParams().klt_window_px;
  const cv::Mat flat(450, 800, CV_8UC1, cv::Scalar(40));
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const CornerSignal s(underNoise(flat, 1.0, 8.0, seed));
    double largest = 0.0, sum = 0.0;
    int n = 0;
    for (int v = 0; v < 450; v += 2)
      for (int u = 0; u < 800; u += 2) {
        const double snr = s.snr(cv::Point2f(static_cast<float>(u), static_cast<float>(v)), window);
        largest = std::max(largest, snr);
        sum += snr;
        ++n;
      }
    std::printf("seed %d: noise %.2f, SNR mean %.2f, largest %.2f (threshold %.1f)\n", static_cast<int>(seed),
                s.noiseSigma(), sum / n, largest, threshold);
    EXPECT_LT(largest, threshold);
    EXPECT_GT(sum / n, 0.5);  // the ratio is normalized: noise alone gives about 1 on average
    EXPECT_LT(sum / n, 1.5);
  }
}

TEST(ImageNoise, AFaintCornerUnderTheSameNoiseStandsOut) {
  // A fifth of the light (the squares 32 grey levels apart) under noise of 8.
  const cv::Mat dim = underNoise(checkerboard(800, 450, 40), 0.2, 8.0, 4);
  const CornerSignal s(dim);
  const int window = TrackerParams().klt_window_px;
  for (const cv::Point2f corner : {cv::Point2f(199.5f, 199.5f), cv::Point2f(399.5f, 239.5f)})
    EXPECT_GT(s.snr(corner, window), 2.0 * kMinCornerSnr) << corner;  // measured 10.5 and 11.5
  // The middle of a square: flat, noise alone.
  EXPECT_LT(s.snr(cv::Point2f(220.0f, 220.0f), 9), kMinCornerSnr);
}

TEST(ImageNoise, ATrackerFindsNoCornerInNoiseAndKeepsTheFaintScenes) {
  const CameraModel cam = test::pinholeCamera(800, 450, 400.0);
  const cv::Mat flat(450, 800, CV_8UC1, cv::Scalar(20));
  TrackerParams checked;
  checked.min_corner_snr = kMinCornerSnr;
  FeatureTracker tracker(cam, checked);
  for (std::uint64_t seed = 1; seed <= 3; ++seed)
    EXPECT_TRUE(tracker.track(0.1 * seed, underNoise(flat, 1.0, 8.0, seed), std::nullopt).features.empty());
  // Without the test the same noise is full of corners.
  TrackerParams every_corner;
  every_corner.min_corner_snr = 0.0;
  FeatureTracker unchecked(cam, every_corner);
  EXPECT_GT(unchecked.track(0.0, underNoise(flat, 1.0, 8.0, 1), std::nullopt).features.size(), 50u);
  // The faint checkerboard keeps its corners (8 x 4 inner ones away from the border, at most).
  FeatureTracker dim(cam, checked);
  EXPECT_GE(dim.track(0.0, underNoise(checkerboard(800, 450, 80), 0.2, 8.0, 5), std::nullopt).features.size(), 20u);
}

}  // namespace
}  // namespace vi_ekf_slam
