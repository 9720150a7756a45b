// One map point: three error-state entries `l` and how to read them.
//
// kCartesian: l = p_s_l, the point in the strapdown frame (the paper's parameterization).
// kInverseDepth: l = (u, v, rho) = normalized image coordinates and inverse depth of the point
//   in a fixed anchor frame {a} (the estimated camera frame when the point was first seen):
//   p_s_l = p_s_a + R_s_a [u, v, 1]^T / rho. The anchor is a constant of the parameterization,
//   not a state; the point's correlation with the pose error at initialization is carried by
//   its cross-covariance, exactly as for a Cartesian point. The map is almost linear in rho, so
//   a point of unknown depth is a Gaussian in l, unlike a Cartesian point at a guessed depth.
//   When the state estimates the camera-IMU extrinsic, the anchor is the body pose at the first
//   view (a constant) composed with the *estimated* extrinsic: the anchor rides on the extrinsic
//   (FilterState::boxplus moves it), so the ray starts at the camera the extrinsic places. A
//   constant camera anchor would make l absorb the extrinsic's error scaled by the uncertain rho,
//   a product the linearized filter drops: it gained centimetres of extrinsic information from
//   two images a millisecond apart.
#pragma once

#include "vi_ekf_slam/core/so3.h"

namespace vi_ekf_slam {

enum class LandmarkKind { kCartesian, kInverseDepth };

struct Landmark {
  LandmarkKind kind = LandmarkKind::kCartesian;
  Vec3 l = Vec3::Zero();
  Vec3 p_s_a = Vec3::Zero();      ///< anchor origin in {s} (inverse depth only)
  Mat3 R_s_a = Mat3::Identity();  ///< anchor orientation in {s} (inverse depth only)
  /// A consider state (Schmidt-Kalman): measurements correct the rest of the state through its
  /// cross-covariance but never the point itself, whose mean and covariance they leave as they
  /// were (kalman_update.h). The map's dormant points, with map.dormant_consider.
  bool consider = false;

  static Landmark cartesian(const Vec3& p_s_l) {
    Landmark lm;
    lm.l = p_s_l;
    return lm;
  }

  /// The point in {s}; M = d(point)/d(l). Inverse depths below 1e-6 m^-1 are read as 1e-6
  /// (a point a thousand kilometres away) so the position stays finite.
  Vec3 position(Mat3* M = nullptr) const {
    if (kind == LandmarkKind::kCartesian) {
      if (M) M->setIdentity();
      return l;
    }
    const double rho = std::abs(l.z()) < 1e-6 ? (l.z() < 0 ? -1e-6 : 1e-6) : l.z();
    const Vec3 m = R_s_a * Vec3(l.x(), l.y(), 1.0);
    if (M) {
      M->col(0) = R_s_a.col(0) / rho;
      M->col(1) = R_s_a.col(1) / rho;
      M->col(2) = -m / (rho * rho);
    }
    return p_s_a + m / rho;
  }

  /// d(l)/d(point): the inverse of position()'s M, in closed form (stable for small rho).
  Mat3 paramsFromPointJacobian() const {
    if (kind == LandmarkKind::kCartesian) return Mat3::Identity();
    const double rho = std::abs(l.z()) < 1e-6 ? (l.z() < 0 ? -1e-6 : 1e-6) : l.z();
    Mat3 B_inv;  // inverse of [e1/rho, e2/rho, -(u, v, 1)/rho^2]
    B_inv << rho, 0.0, -l.x() * rho, 0.0, rho, -l.y() * rho, 0.0, 0.0, -rho * rho;
    return B_inv * R_s_a.transpose();
  }

  /// The entries that would represent the point p_s (given in {s}) in this parameterization
  /// (same anchor).
  Vec3 paramsOf(const Vec3& p_s) const {
    if (kind == LandmarkKind::kCartesian) return p_s;
    const Vec3 p_a = R_s_a.transpose() * (p_s - p_s_a);
    return Vec3(p_a.x() / p_a.z(), p_a.y() / p_a.z(), 1.0 / p_a.z());
  }

  /// The point's derivative w.r.t. the extrinsic's errors [p_b_c, theta] (R_b_c = Exp(theta)
  /// R_b_c) at fixed l, the anchor riding on the extrinsic whose estimated rotation is R_b_c. Zero
  /// for a Cartesian point.
  Eigen::Matrix<double, 3, 6> extrinsicJacobian(const Mat3& R_b_c) const {
    Eigen::Matrix<double, 3, 6> J = Eigen::Matrix<double, 3, 6>::Zero();
    if (kind == LandmarkKind::kCartesian) return J;
    const Mat3 R_s_ab = R_s_a * R_b_c.transpose();  // the anchor body's orientation
    J << R_s_ab, -skew(position() - p_s_a) * R_s_ab;
    return J;
  }

  /// The anchor of the same body pose under another extrinsic (from -> to): l is unchanged, so an
  /// inverse-depth point moves with the camera the new extrinsic places. A Cartesian point is kept.
  Landmark withExtrinsic(const Mat3& R_b_c_from, const Vec3& p_b_c_from, const Mat3& R_b_c_to,
                         const Vec3& p_b_c_to) const {
    Landmark out = *this;
    if (kind == LandmarkKind::kCartesian) return out;
    const Mat3 R_s_ab = R_s_a * R_b_c_from.transpose();
    const Vec3 p_s_ab = p_s_a - R_s_ab * p_b_c_from;
    out.R_s_a = R_s_ab * R_b_c_to;
    out.p_s_a = p_s_ab + R_s_ab * p_b_c_to;
    return out;
  }

  /// The same point after the frame change y' = R y + t (l is unchanged for inverse depth,
  /// whose anchor moves instead).
  Landmark transformed(const Mat3& R, const Vec3& t) const {
    Landmark out = *this;
    if (kind == LandmarkKind::kCartesian) {
      out.l = R * l + t;
    } else {
      out.p_s_a = R * p_s_a + t;
      out.R_s_a = R * R_s_a;
    }
    return out;
  }
};

}  // namespace vi_ekf_slam
