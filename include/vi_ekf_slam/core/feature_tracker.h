// The visual front end (OpenCV): corners spread over a grid (Shi-Tomasi or FAST), pyramidal
// Lucas-Kanade tracking from frame to frame with the gyro-predicted rotation as initial guess,
// a forward-backward check and RANSAC on the epipolar constraint. Tracks keep their id while
// they live; ids are never reused, so a lost track ends its landmark.
#pragma once

#include <cstdint>
#include <optional>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <string>
#include <vector>

#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/image_noise.h"
#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {

struct TrackerParams {
  enum class Detector { kShiTomasi, kFast };
  Detector detector = Detector::kShiTomasi;
  int max_tracks = 100;  ///< target number of tracks
  int grid_cols = 8;     ///< new corners are spread over this grid
  int grid_rows = 6;
  double min_distance_px = 12.0;  ///< minimum distance between corners [px]
  double quality_level = 0.01;    ///< Shi-Tomasi quality relative to the best corner
  int fast_threshold = 20;        ///< FAST intensity threshold [gray levels]
  /// A corner, new or tracked, is kept only where its KLT window holds this many times the
  /// gradient the image's own noise gives (image_noise.h) [ratio]; 0 keeps every corner. Both
  /// detectors rank corners against each other, so without it an image of pure noise (darkness at
  /// a high gain) is full of corners that are measurements of nothing. Off by default: 5 (noise
  /// alone reaches about 3) makes such images blind, but costs a little where a faint scene was
  /// still tracked (docs/evaluation.md, darkness).
  double min_corner_snr = 0.0;
  int klt_window_px = 15;            ///< KLT window size [px]
  int klt_pyramid_levels = 3;        ///< KLT pyramid levels above the image
  double fb_threshold_px = 1.0;      ///< forward-backward error bound [px]
  double ransac_threshold_px = 1.0;  ///< epipolar RANSAC threshold (undistorted) [px]
  int border_px = 8;                 ///< corners this close to the border are dropped [px]
  /// New corners are searched only once the tracks fall below this fraction of max_tracks
  /// [ratio]; 1 searches in every image that lost a track. The search is most of the tracker's
  /// time: a lower value trades a few tracks for much of it (bench/README.md).
  double redetect_fraction = 1.0;
  /// Images wider than this are shrunk to this width before tracking [px]; 0 tracks at full
  /// size. Every pixel quantity of the tracker and of the filter (thresholds, pixel noise,
  /// parallax) then refers to the shrunk image. Set at start-up.
  int max_image_width_px = 800;
  /// Describe each new corner (ORB, 256 bits) and look again where the filter expects a landmark
  /// whose track ended (CameraFrame::search), so the map's points can be found again.
  bool descriptors = true;
  /// Empty if usable, otherwise what is wrong.
  std::string validate() const;
};
std::optional<TrackerParams::Detector> detectorFromString(const std::string& s);

/// The intrinsics of the image the tracker works on: `full` itself, or, when it is wider than
/// max_width_px (> 0), the image shrunk to that width by cv::resize (pixel centres map as
/// u' = (u + 0.5) * s - 0.5, so fx and cx scale with s; distortion acts on normalized
/// coordinates and is unchanged).
CameraIntrinsics trackingIntrinsics(const CameraIntrinsics& full, int max_width_px);
/// `img` at the size of `tracking` (area interpolation; the same Mat when it already is).
cv::Mat toTrackingResolution(const cv::Mat& img, const CameraIntrinsics& tracking);

struct TrackerStats {
  int tracked = 0;           ///< tracks continued from the previous image
  int lost = 0;              ///< KLT failures and tracks that left the image
  int fb_rejected = 0;       ///< failed the forward-backward check
  int noise_rejected = 0;    ///< tracks whose window in this image holds no more than noise
  int ransac_rejected = 0;   ///< epipolar outliers
  int detected = 0;          ///< new tracks
  int total = 0;             ///< tracks in this image
  double noise_sigma = 0.0;  ///< the image's noise (imageNoiseSigma) [grey levels]
};

class FeatureTracker {
 public:
  FeatureTracker(const CameraModel& camera, const TrackerParams& params);

  /// Tracks into a mono8 image. R_cur_prev: rotation of the camera from the previous image to
  /// this one (vectors in the previous camera frame to the current one), e.g. from the gyro;
  /// it only seeds KLT. Returns the features of this image with their track ids.
  CameraFrame track(double timestamp, const cv::Mat& mono8, const std::optional<Eigen::Matrix3d>& R_cur_prev);

  const TrackerStats& stats() const { return stats_; }
  const TrackerParams& params() const { return params_; }
  /// The camera of the images it tracks (see trackingIntrinsics).
  const CameraModel& camera() const { return camera_; }
  void setParams(const TrackerParams& params) { params_ = params; }
  /// Forgets every track (ids keep increasing).
  void reset();

  /// The image in colour with every track, its recent path and its id (for the debug topic).
  cv::Mat drawTracks(const cv::Mat& mono8) const;

 private:
  struct Track {
    std::int64_t id;
    cv::Point2f uv;
    int age;
    std::vector<cv::Point2f> history;
    std::optional<Descriptor> descriptor;         ///< where it was detected
    std::optional<Descriptor> latest_descriptor;  ///< described again every kDescribeEveryFrames
  };
  void detect(const cv::Mat& img);
  /// The corner at p of the last tracked image stands above its noise (min_corner_snr).
  bool aboveNoise(const cv::Point2f& p) const;
  std::optional<CornerSignal> signal_;  ///< of the last tracked image, if min_corner_snr > 0
  /// CameraFrame::search on `img` (the last tracked image): corners in each region (within four
  /// of its standard deviations, at most 64 px away), away from the tracks, with descriptors.
  std::vector<FeatureObservation> searchCorners(const cv::Mat& img, const std::vector<SearchRegion>& regions);
  /// CameraFrame::adopt: a corner of the last search becomes a track.
  std::int64_t adoptCorner(const FeatureObservation& corner);
  cv::Ptr<cv::ORB> orb_ = cv::ORB::create();
  int images_since_described_ = 0;  ///< the tracks are described again every kDescribeEveryFrames
  cv::Point2f predict(const cv::Point2f& uv, const Eigen::Matrix3d& R_cur_prev) const;

  CameraModel camera_;
  TrackerParams params_;
  std::vector<cv::Mat> prev_pyramid_;
  cv::Mat prev_image_;
  std::vector<Track> tracks_;
  std::int64_t next_id_ = 0;
  TrackerStats stats_;
};

}  // namespace vi_ekf_slam
