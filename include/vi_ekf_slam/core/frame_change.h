// Changes of the reference frame of the whole state: the composition step (paper eq. 31-33),
// the switch between world-centric and sensor-centric mechanizations, and the navigation-frame
// view of a sensor-centric state. All three are maps whose Jacobian J has the structure
//
//          [ J_motion        0        ]   motion rows: a small dense block (15 or 21, square/rect.)
//     J =  [ A_1        L_1            ]   landmark i: a 3x3 block L_i on its own entries (a
//          [ A_2               L_2     ]   rotation for Cartesian points, I for inverse depth)
//                                          plus A_i acting on one position and one rotation block
//
// so P' = J P J^T is computed in O(n^2) with block operations, never as a dense n^3 product.
#pragma once

#include <vector>

#include "vi_ekf_slam/core/filter_state.h"

namespace vi_ekf_slam {

struct FrameChangeJacobian {
  Eigen::MatrixXd J_motion;  ///< motion_out x motion_in
  int pos_col = 0;           ///< motion column block that A_pos[i] acts on
  int rot_col = 0;           ///< motion column block that A_rot[i] acts on
  std::vector<Mat3> L;       ///< d(landmark_out_i)/d(landmark_in_i)
  std::vector<Mat3> A_pos;   ///< d(landmark_out_i)/d(motion[pos_col..+3])
  std::vector<Mat3> A_rot;   ///< d(landmark_out_i)/d(motion[rot_col..+3])
};

/// Computes J P J^T for a structured J (see above).
Eigen::MatrixXd applyFrameChange(const Eigen::MatrixXd& P, const FrameChangeJacobian& J);
/// Dense J (for tests and small problems only).
Eigen::MatrixXd denseJacobian(const FrameChangeJacobian& J, int num_landmarks);

/// The composition step (eq. 31-33): the strapdown frame is reset to the current body frame.
/// Only for sensor-centric states. Biases are untouched; p_n_s, q_n_s are composed (eq. 32).
FrameChangeJacobian compositionJacobian(const FilterState& state);
/// second_order: the covariance keeps, for every inverse-depth landmark, the term of second order
/// that the Jacobian leaves out (compositionSecondOrderTerm).
void compose(FilterState& state, bool second_order = false);
/// An inverse-depth landmark's parameters follow the pose error through the moved anchor by a
/// Jacobian proportional to its inverse depth (rho for the bearing, rho^2 for rho itself), taken at
/// the estimate. With rho itself uncertain, the product of its error and the pose error is a term
/// the first order leaves out: its covariance, (sigma_rho / rho)^2 D A P_pose A^T D with
/// D = diag(1, 1, 2) and A = [A_pos A_rot] (independent errors assumed), is what a new point's
/// bearing is unsure of beyond the first order. Small once the depth is known; large for a point at
/// its prior depth, whose updates otherwise make the velocity over-confident on a slow start.
/// Landmark i's 3x3 term, for the Jacobian J of the composition of `state`.
Mat3 compositionSecondOrderTerm(const FilterState& state, const FrameChangeJacobian& J, int i);

/// Converts the state between world-centric and sensor-centric layouts, keeping the map and
/// every navigation-frame quantity with its covariance. World -> sensor puts {s} at the current
/// body frame (like a composition). Between the two sensor-centric variants only the tag changes.
FrameChangeJacobian worldToSensorJacobian(const FilterState& state);
FrameChangeJacobian sensorToWorldJacobian(const FilterState& state);
/// Motion rows of sensorToWorldJacobian() (15 x 21), which need no landmark.
Eigen::MatrixXd sensorToWorldMotionJacobian(const MotionState& x);
void switchMechanization(FilterState& state, Mechanization target);

}  // namespace vi_ekf_slam
