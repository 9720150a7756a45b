// The visual front end on synthetic images whose true motion is known: KLT seeded by the gyro's
// rotation follows a rotation-only homography to a fraction of a pixel, corners respect the grid
// quota, spacing, border and the quality floor relative to the best corner, the search waits
// for redetect_fraction, and bad images
// (another size, no texture) reset or starve the tracker without crashing. ORB descriptors
// computed in windows equal those of the whole image.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <opencv2/imgproc.hpp>
#include <set>

#include "test_helpers.h"
#include "vi_ekf_slam/core/feature_tracker.h"
#include "vi_ekf_slam/core/orb_descriptors.h"
#include "vi_ekf_slam/core/so3.h"

// After Eigen (pulled in above): OpenCV's Eigen bridge needs it first.
#include <opencv2/core/eigen.hpp>

namespace vi_ekf_slam {
namespace {

/// Blurred noise: corners everywhere, smooth enough for KLT. amplitude scales the contrast.
cv::Mat texture(int width, int height, double amplitude, unsigned seed) {
  cv::Mat noise(height, width, CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 2.0);
  cv::normalize(noise, noise, 0.0, 1.0, cv::NORM_MINMAX);
  cv::Mat out;
  noise.convertTo(out, CV_8U, amplitude, 128.0 - amplitude / 2.0);
  return out;
}

cv::Matx33d intrinsicMatrix(const CameraModel& cam) {
  const auto& k = cam.intrinsics();
  return {k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0};
}

/// Where a pixel of the previous image lands after the camera rotated by R_cur_prev.
cv::Point2d rotatePixel(const cv::Matx33d& H, const Eigen::Vector2d& uv) {
  const cv::Vec3d q = H * cv::Vec3d(uv.x(), uv.y(), 1.0);
  return {q[0] / q[2], q[1] / q[2]};
}

TEST(FeatureTracker, GyroPredictionLetsKltFollowALargeRotation) {
  const CameraModel cam = test::pinholeCamera(640, 480, 400.0);
  TrackerParams p;
  p.max_tracks = 100;
  FeatureTracker tracker(cam, p);
  const cv::Mat img0 = texture(cam.width(), cam.height(), 200.0, 1);
  const CameraFrame f0 = tracker.track(0.0, img0, std::nullopt);
  ASSERT_GE(f0.features.size(), 90u);

  // The camera turns 10 deg about its y axis (about 70 px of image motion at the centre, more
  // than the 3-level pyramid's reach of 56 px) and 2 deg about its optical axis.
  const Eigen::Matrix3d R_cur_prev = expSO3(Vec3(0.0, 10.0, 2.0) * M_PI / 180.0);
  cv::Matx33d R;
  cv::eigen2cv(R_cur_prev, R);
  const cv::Matx33d K = intrinsicMatrix(cam);
  const cv::Matx33d H = K * R * K.inv();
  cv::Mat img1;
  cv::warpPerspective(img0, img1, cv::Mat(H), img0.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);

  std::map<std::int64_t, Eigen::Vector2d> before;
  for (const auto& f : f0.features) before[f.id] = f.uv;
  // Tracks whose point stays well inside the new image (away from the reflected border).
  int visible = 0;
  for (const auto& [id, uv] : before) {
    const cv::Point2d q = rotatePixel(H, uv);
    if (q.x > 30 && q.y > 30 && q.x < cam.width() - 30 && q.y < cam.height() - 30) ++visible;
  }
  ASSERT_GE(visible, 40);

  FeatureTracker unseeded = tracker;
  const CameraFrame f1 = tracker.track(0.1, img1, R_cur_prev);
  std::vector<double> errors;
  for (const auto& f : f1.features) {
    const auto it = before.find(f.id);
    if (it == before.end()) continue;
    const cv::Point2d q = rotatePixel(H, it->second);
    errors.push_back(std::hypot(f.uv.x() - q.x, f.uv.y() - q.y));
  }
  const int continued = static_cast<int>(errors.size());
  EXPECT_GE(continued, static_cast<int>(0.9 * visible));
  std::sort(errors.begin(), errors.end());
  ASSERT_FALSE(errors.empty());
  const double median = errors[errors.size() / 2], p90 = errors[errors.size() * 9 / 10];
  std::cout << "continued " << continued << " (" << visible << " well inside), error median " << median << " px, 90% "
            << p90 << " px, worst " << errors.back() << " px\n";
  // Translation-only KLT on a rotated, re-interpolated image: a fraction of a pixel, not zero.
  EXPECT_LT(median, 0.25);
  EXPECT_LT(p90, 0.5);
  EXPECT_LT(errors.back(), 1.5);
  EXPECT_EQ(tracker.stats().tracked, continued);
  EXPECT_EQ(tracker.stats().total, static_cast<int>(f1.features.size()));

  // Without the prediction the same images lose most of the tracks (or reject them).
  const CameraFrame g1 = unseeded.track(0.1, img1, std::nullopt);
  int unseeded_continued = 0;
  for (const auto& f : g1.features) unseeded_continued += before.count(f.id) ? 1 : 0;
  EXPECT_LT(unseeded_continued, continued / 2);
}

TEST(FeatureTracker, NewCornersFillTheGridWithSpacingAndBorder) {
  const CameraModel cam = test::pinholeCamera(640, 480, 400.0);
  TrackerParams p;
  p.max_tracks = 96;  // 2 per cell of the 8 x 6 grid
  FeatureTracker tracker(cam, p);
  const CameraFrame f = tracker.track(0.0, texture(cam.width(), cam.height(), 200.0, 2), std::nullopt);
  ASSERT_EQ(static_cast<int>(f.features.size()), p.max_tracks);
  EXPECT_EQ(tracker.stats().detected, p.max_tracks);
  std::map<int, int> per_cell;
  std::set<std::int64_t> ids;
  for (size_t i = 0; i < f.features.size(); ++i) {
    const Eigen::Vector2d& a = f.features[i].uv;
    ids.insert(f.features[i].id);
    EXPECT_GE(a.x(), p.border_px);
    EXPECT_GE(a.y(), p.border_px);
    EXPECT_LE(a.x(), cam.width() - 1 - p.border_px);
    EXPECT_LE(a.y(), cam.height() - 1 - p.border_px);
    const int cell = static_cast<int>(a.y() * p.grid_rows / cam.height()) * p.grid_cols +
                     static_cast<int>(a.x() * p.grid_cols / cam.width());
    ++per_cell[cell];
    for (size_t j = 0; j < i; ++j)
      EXPECT_GE((a - f.features[j].uv).norm(), p.min_distance_px - 1.0) << "corners " << i << " and " << j;
  }
  EXPECT_EQ(ids.size(), f.features.size()) << "ids are unique";
  for (const auto& [cell, n] : per_cell) EXPECT_LE(n, 2) << "cell " << cell;
  EXPECT_EQ(per_cell.size(), 48u) << "every cell of a uniformly textured image gets its quota";
}

TEST(FeatureTracker, WeakTextureBelowTheQualityFloorGetsNoCorners) {
  // A strongly textured 160 x 160 patch (2 x 2 grid cells) in an image whose rest carries the
  // same pattern at 1/50 of the contrast: corner responses there are ~1/2500 of the best, below
  // quality_level = 0.01 of it, so the empty cells stay empty although they are below quota.
  const CameraModel cam = test::pinholeCamera(640, 480, 400.0);
  TrackerParams p;
  p.max_tracks = 96;
  cv::Mat img = texture(cam.width(), cam.height(), 4.0, 3);
  const cv::Rect strong(0, 0, 160, 160);
  texture(cam.width(), cam.height(), 200.0, 3)(strong).copyTo(img(strong));
  const double reach = 160 + p.min_distance_px;
  FeatureTracker tracker(cam, p);
  const CameraFrame f = tracker.track(0.0, img, std::nullopt);
  // The patch's 4 cells get their quota of 2; the patch's edge is a corner for a few more.
  EXPECT_GE(f.features.size(), 8u);
  for (const auto& feat : f.features) EXPECT_TRUE(feat.uv.x() < reach && feat.uv.y() < reach);

  // With the floor lowered below the weak texture's responses, the other cells are filled too:
  // the floor, not a lack of corners, kept them empty.
  p.quality_level = 1e-5;
  FeatureTracker permissive(cam, p);
  int outside = 0;
  for (const auto& feat : permissive.track(0.0, img, std::nullopt).features)
    outside += feat.uv.x() > reach || feat.uv.y() > reach;
  EXPECT_GT(outside, 30);
}

/// The image moved dx px to the left (reflected at the right edge), as a pan would.
cv::Mat shiftedLeft(const cv::Mat& img, double dx) {
  const cv::Matx23d A(1.0, 0.0, -dx, 0.0, 1.0, 0.0);
  cv::Mat out;
  cv::warpAffine(img, out, A, img.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  return out;
}

/// The smallest integer shift that pushes between `lost_min` and `lost_max` corners out over the
/// left border, with every corner at least 1 px from that border afterwards (so KLT's sub-pixel
/// noise cannot decide); 0 if there is none.
int shiftLosing(const CameraFrame& f, int border_px, size_t lost_min, size_t lost_max) {
  for (int dx = 1; dx < 200; ++dx) {
    size_t lost = 0;
    bool clear = true;
    for (const auto& feat : f.features) {
      const double x = feat.uv.x() - dx;
      lost += x < border_px;
      clear = clear && std::abs(x - border_px) > 1.0;
    }
    if (clear && lost >= lost_min && lost <= lost_max) return dx;
  }
  return 0;
}

TEST(FeatureTracker, RedetectFractionDefersTheSearchUntilEnoughTracksAreLost) {
  const CameraModel cam = test::pinholeCamera(640, 480, 400.0);
  TrackerParams p;
  p.max_tracks = 40;
  p.redetect_fraction = 0.9;  // search again below 36 tracks
  const cv::Mat img0 = texture(cam.width(), cam.height(), 200.0, 7);
  FeatureTracker lazy(cam, p);
  const CameraFrame f0 = lazy.track(0.0, img0, std::nullopt);
  ASSERT_EQ(static_cast<int>(f0.features.size()), p.max_tracks);
  const int dx1 = shiftLosing(f0, p.border_px, 1, 3);
  ASSERT_GT(dx1, 0);

  // A few tracks leave the image: 37-39 are left, above 36, so nothing is searched.
  const CameraFrame f1 = lazy.track(0.1, shiftedLeft(img0, dx1), std::nullopt);
  EXPECT_GE(lazy.stats().lost, 1);
  EXPECT_EQ(lazy.stats().detected, 0);
  EXPECT_GE(f1.features.size(), 37u);
  EXPECT_LT(f1.features.size(), 40u);

  // The default (1.0) searches as soon as one track is missing.
  TrackerParams e = p;
  e.redetect_fraction = 1.0;
  FeatureTracker eager(cam, e);
  ASSERT_EQ(static_cast<int>(eager.track(0.0, img0, std::nullopt).features.size()), p.max_tracks);
  EXPECT_EQ(static_cast<int>(eager.track(0.1, shiftedLeft(img0, dx1), std::nullopt).features.size()), p.max_tracks);
  EXPECT_GE(eager.stats().detected, 1);

  // More tracks leave, down below 36 in total: the search runs and fills up to max_tracks again.
  const int dx2 = shiftLosing(f1, p.border_px, f1.features.size() - 35, f1.features.size() - 1);
  ASSERT_GT(dx2, 0);
  const CameraFrame f2 = lazy.track(0.2, shiftedLeft(img0, dx1 + dx2), std::nullopt);
  EXPECT_LT(lazy.stats().tracked, 36);
  EXPECT_GT(lazy.stats().detected, 0);
  EXPECT_EQ(static_cast<int>(f2.features.size()), p.max_tracks);
}

TEST(FeatureTracker, ImagesOfAnotherSizeOrWithoutTextureRestartTracking) {
  const CameraModel cam = test::pinholeCamera(640, 480, 400.0);
  TrackerParams p;
  p.max_tracks = 60;
  FeatureTracker tracker(cam, p);
  const CameraFrame f0 = tracker.track(0.0, texture(cam.width(), cam.height(), 200.0, 4), std::nullopt);
  ASSERT_EQ(static_cast<int>(f0.features.size()), p.max_tracks);
  std::int64_t max_id = 0;
  for (const auto& f : f0.features) max_id = std::max(max_id, f.id);

  // Another size: the old tracks cannot continue; new ones start with new ids.
  const CameraFrame f1 = tracker.track(0.1, texture(320, 240, 200.0, 5), std::nullopt);
  EXPECT_EQ(tracker.stats().tracked, 0);
  EXPECT_FALSE(f1.features.empty());
  for (const auto& f : f1.features) EXPECT_GT(f.id, max_id) << "ids are never reused";

  // A covered lens (uniform image): nothing to track or detect, and no crash.
  const CameraFrame f2 = tracker.track(0.2, cv::Mat(cam.height(), cam.width(), CV_8UC1, cv::Scalar(90)), std::nullopt);
  EXPECT_TRUE(f2.features.empty());
  EXPECT_EQ(tracker.stats().total, 0);
  // And it picks up again on the next textured image.
  EXPECT_EQ(
      static_cast<int>(tracker.track(0.3, texture(cam.width(), cam.height(), 200.0, 6), std::nullopt).features.size()),
      p.max_tracks);
}

}  // namespace
TEST(FeatureTracker, WideImagesAreTrackedShrunkWithTheirOwnIntrinsics) {
  // A 1280x720 camera tracked at max_image_width_px 800: a bright spot rendered at the projection
  // of a 3D point in the full image lands, after toTrackingResolution, where the tracking
  // intrinsics project the same point (the pixel-centre convention of cv::resize).
  CameraIntrinsics full;
  full.width = 1280;
  full.height = 720;
  full.fx = 906.26;
  full.fy = 906.55;
  full.cx = 642.9;
  full.cy = 353.14;
  const CameraIntrinsics t = trackingIntrinsics(full, 800);
  EXPECT_EQ(t.width, 800);
  EXPECT_EQ(t.height, 450);
  EXPECT_TRUE(t.validate().empty());
  // Not wider than the bound, or no bound: unchanged.
  EXPECT_EQ(trackingIntrinsics(full, 1280).fx, full.fx);
  EXPECT_EQ(trackingIntrinsics(full, 0).width, 1280);
  const CameraModel cam_full(full), cam_t(t);
  for (const Eigen::Vector3d& p_c : {Eigen::Vector3d(0.31, -0.17, 2.0), Eigen::Vector3d(-0.9, 0.4, 1.5)}) {
    Eigen::Vector2d uv_full, uv_t;
    ASSERT_TRUE(cam_full.project(p_c, &uv_full));
    ASSERT_TRUE(cam_t.project(p_c, &uv_t));
    cv::Mat img(full.height, full.width, CV_32F);
    for (int r = 0; r < img.rows; ++r) {
      for (int c = 0; c < img.cols; ++c) {
        const double d2 = std::pow(c - uv_full.x(), 2) + std::pow(r - uv_full.y(), 2);
        img.at<float>(r, c) = static_cast<float>(200.0 * std::exp(-d2 / (2.0 * 4.0 * 4.0)));
      }
    }
    cv::Mat img8;
    img.convertTo(img8, CV_8U);
    const cv::Mat small = toTrackingResolution(img8, t);
    ASSERT_EQ(small.cols, 800);
    ASSERT_EQ(small.rows, 450);
    const cv::Moments m = cv::moments(small);
    EXPECT_NEAR(m.m10 / m.m00, uv_t.x(), 0.05);
    EXPECT_NEAR(m.m01 / m.m00, uv_t.y(), 0.05);
  }
  EXPECT_EQ(toTrackingResolution(cv::Mat(450, 800, CV_8U, cv::Scalar(0)), t).cols, 800);
}

TEST(OrbDescriptors, WindowsDescribeAsTheWholeImageDoes) {
  const cv::Mat img = texture(640, 480, 200.0, 11);
  cv::Ptr<cv::ORB> orb = cv::ORB::create();
  // Points everywhere, sub-pixel, the border's neighbourhood included (those ORB drops).
  cv::RNG rng(5);
  std::vector<cv::Point2f> pts;
  for (int i = 0; i < 400; ++i) pts.emplace_back(rng.uniform(-5.0f, 645.0f), rng.uniform(-5.0f, 485.0f));
  for (float b : {30.5f, 31.0f, 31.5f, 608.0f, 608.5f, 609.0f}) {
    pts.emplace_back(b, 240.3f);
    pts.emplace_back(320.7f, b - 160.0f);
  }
  for (float h : {100.5f, 101.5f, 250.5f, 251.5f}) pts.emplace_back(h, h + 1.0f);  // ORB rounds half to even
  // The whole image's descriptors, as cv::ORB gives them.
  std::vector<cv::KeyPoint> kps;
  for (size_t i = 0; i < pts.size(); ++i) kps.emplace_back(pts[i], 31.0f, -1.0f, 0.0f, 0, static_cast<int>(i));
  cv::Mat desc;
  orb->compute(img, kps, desc);
  std::vector<std::optional<Descriptor>> whole(pts.size());
  for (int k = 0; k < desc.rows; ++k) {
    Descriptor d;
    std::copy(desc.ptr<std::uint8_t>(k), desc.ptr<std::uint8_t>(k) + d.size(), d.begin());
    whole[static_cast<size_t>(kps[static_cast<size_t>(k)].class_id)] = d;
  }
  // Few points at a time are described in windows, all at once on the whole image.
  int described = 0, dropped = 0;
  for (size_t i = 0; i < pts.size(); i += 3) {
    const std::vector<cv::Point2f> few(pts.begin() + static_cast<long>(i),
                                       pts.begin() + static_cast<long>(std::min(pts.size(), i + 3)));
    const auto got = describeOrb(*orb, img, few);
    ASSERT_EQ(got.size(), few.size());
    for (size_t j = 0; j < few.size(); ++j) {
      ASSERT_EQ(got[j].has_value(), whole[i + j].has_value()) << few[j];
      if (got[j]) {
        EXPECT_EQ(*got[j], *whole[i + j]) << few[j];
        ++described;
      } else {
        ++dropped;
      }
    }
  }
  EXPECT_GT(described, 300);
  EXPECT_GT(dropped, 20);  // near the border
  const auto all = describeOrb(*orb, img, pts);
  for (size_t i = 0; i < pts.size(); ++i) EXPECT_EQ(all[i], whole[i]);
}

}  // namespace vi_ekf_slam
