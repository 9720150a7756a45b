// The frames the node's outputs are expressed in. The filter estimates the IMU in its own
// gravity-aligned world, which starts over at every reset; a robot's graph (REP-105) wants the
// pose of its base (base_link, not the IMU) in `odom`, a frame in which that pose is continuous.
//   publish_tf odom  : odom_frame -> base_frame (base_frame "": the IMU frame); odometry, path and
//                      landmarks in odom_frame. base_frame <- IMU comes from TF (a URDF).
//   publish_tf none  : the same frames, no TF (another node owns odom -> base_link).
//   publish_tf world : world_frame -> IMU frame, the filter's world as it is (restarts at resets).
#pragma once

#include <Eigen/Geometry>
#include <nav_msgs/Odometry.h>
#include <optional>
#include <string>
#include <tf2/buffer_core.h>

namespace vi_ekf_slam::glue {

enum class TfMode { kNone, kOdom, kWorld };
std::optional<TfMode> tfModeFromString(const std::string& s);
std::string toString(TfMode m);

/// Odometry of a frame rigidly attached to the IMU (a robot's base), from the IMU's odometry.
/// T_b_i: the IMU in the base frame. Pose covariance [position, global rotation vector] and twist
/// covariance [linear, angular] are carried through the first-order (exact for rotation) maps.
nav_msgs::Odometry attachedFrameOdometry(const nav_msgs::Odometry& imu, const Eigen::Isometry3d& T_b_i,
                                         const std::string& base_frame);

/// The same odometry expressed in another fixed frame o, given the old fixed frame w in o (T_o_w).
/// The twist (in the child frame) is unchanged; the pose covariance rotates with R_o_w.
nav_msgs::Odometry reexpressed(const nav_msgs::Odometry& odom, const Eigen::Isometry3d& T_o_w,
                               const std::string& frame);

/// The rotation about z and translation that take `T_w_b` onto `T_o_b` as closely as gravity
/// allows (the yaw of the least-squares rotation in the horizontal plane, then the position).
Eigen::Isometry3d gravityAlignedOffset(const Eigen::Isometry3d& T_o_b, const Eigen::Isometry3d& T_w_b);

/// Turns the IMU odometry of the filter into the published one, and keeps odom continuous across
/// the filter's restarts: after a reset, the new world is placed so that the first new pose
/// continues the last published one (yaw and position; roll and pitch are the filter's).
class OutputFrames {
 public:
  OutputFrames(TfMode mode, std::string world_frame, std::string odom_frame, std::string base_frame);

  TfMode mode() const { return mode_; }
  /// The fixed frame of the outputs (odom_frame or world_frame).
  const std::string& fixedFrame() const { return mode_ == TfMode::kWorld ? world_frame_ : odom_frame_; }
  /// The frame the published odometry (and TF) moves: the IMU frame in world mode, else base_frame
  /// (the IMU frame when empty).
  std::string movedFrame(const std::string& imu_frame) const {
    return mode_ == TfMode::kWorld || base_frame_.empty() ? imu_frame : base_frame_;
  }
  /// Looks up base_frame <- imu_frame once (when they differ). "" when ready, else why not.
  std::string prepare(const std::string& imu_frame, const tf2::BufferCore* tf);
  /// The published odometry from the IMU's odometry in the filter's world (z up); needs prepare().
  nav_msgs::Odometry odometry(const nav_msgs::Odometry& imu_in_world);
  /// The filter's world in the fixed frame of the outputs (identity before the first odometry).
  Eigen::Isometry3d fixedFromWorld() const { return T_o_w_.value_or(Eigen::Isometry3d::Identity()); }
  /// The filter started over: its next pose continues the last published one.
  void filterRestarted() {
    T_o_w_.reset();
    world_is_map_ = false;
  }
  /// Time went back (a replayed bag looped): odom starts over with the filter.
  void forget() {
    T_o_w_.reset();
    last_T_o_b_.reset();
    T_o_m_ = Eigen::Isometry3d::Identity();
    world_is_map_ = false;
  }
  /// The filter's world is the kept map's (a run that starts an empty map): the map's frame is
  /// placed in odom where this world is.
  void worldIsMap() { world_is_map_ = true; }
  /// The filter's world moved into the kept map by T_m_n (VioPipeline relocalized it).
  /// keep_odom (a map_frame is set): odom stays continuous and map -> odom takes the correction;
  /// else odom rejoins the map, where it was before the reset (the pose jumps by the correction).
  void relocalized(const Eigen::Isometry3d& T_m_n, bool keep_odom);
  /// The kept map's frame in odom: map_frame -> odom_frame is its inverse (identity until a
  /// relocalization with keep_odom moves odom away from the map).
  const Eigen::Isometry3d& odomFromMap() const { return T_o_m_; }

 private:
  TfMode mode_;
  std::string world_frame_, odom_frame_, base_frame_;
  std::optional<Eigen::Isometry3d> T_b_i_;                   ///< the IMU in the base frame (from TF)
  std::string imu_frame_;                                    ///< the frame T_b_i_ was looked up for
  std::optional<Eigen::Isometry3d> T_o_w_;                   ///< the filter's current world in odom
  std::optional<Eigen::Isometry3d> last_T_o_b_;              ///< the last published base pose
  Eigen::Isometry3d T_o_m_ = Eigen::Isometry3d::Identity();  ///< the kept map's frame in odom
  bool world_is_map_ = false;                                ///< the filter's world is the map's: T_o_m_ follows T_o_w_
};

}  // namespace vi_ekf_slam::glue
