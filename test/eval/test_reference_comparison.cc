// The comparison with a reference of unknown frame and scale, as evo_ape --align --correct_scale
// measures it: the estimate aligned onto the reference, the error in the reference's units and in
// the estimate's metres.
#include <gtest/gtest.h>

#include "scratch_dir.h"

#include <Eigen/Geometry>
#include <cmath>
#include <fstream>
#include <random>

#include "vi_ekf_slam/io/datasets.h"
#include "vi_ekf_slam/eval/reference_comparison.h"

using namespace vi_ekf_slam;

namespace {

std::vector<io::StampedPose> walk(int n) {
  std::vector<io::StampedPose> out;
  for (int i = 0; i < n; ++i) {
    const double t = 0.05 * i;
    io::StampedPose p;
    p.t = 100.0 + t;
    p.p = Vec3(2.0 * std::sin(0.4 * t), 1.5 * std::cos(0.3 * t), 0.2 * std::sin(1.1 * t));
    p.q = Quat(Eigen::AngleAxisd(0.3 * t, Vec3::UnitZ()) * Eigen::AngleAxisd(0.1 * std::sin(t), Vec3::UnitX()));
    out.push_back(p);
  }
  return out;
}

/// `est` seen in another frame: p' = s R p + t, q' = R q.
std::vector<io::StampedPose> transformed(const std::vector<io::StampedPose>& est, double s, const Quat& R,
                                         const Vec3& t) {
  std::vector<io::StampedPose> out = est;
  for (auto& p : out) {
    p.p = s * (R * p.p) + t;
    p.q = R * p.q;
  }
  return out;
}

}  // namespace

TEST(ReferenceComparison, ASimilarReferenceIsMatchedExactlyWithItsScale) {
  const auto est = walk(200);
  const Quat R(Eigen::AngleAxisd(1.2, Vec3(0.2, -0.5, 1.0).normalized()));
  const auto ref = transformed(est, 3.9, R, Vec3(4.0, -2.0, 7.0));
  const auto c = eval::compareWithReference(est, ref, eval::Alignment::kSim3);
  EXPECT_EQ(c.matched, 200);
  EXPECT_NEAR(c.scale, 3.9, 1e-9);
  EXPECT_LT(c.position_rmse_reference_units, 1e-9);
  EXPECT_LT(c.rotation_rmse_deg, 1e-6);
  EXPECT_NEAR(c.reference_path_m, c.estimate_path_m, 1e-9);  // the reference shown in metres
  // A rotated metric reference: SE(3), and position + yaw when only the yaw differs.
  const auto se3 = eval::compareWithReference(est, transformed(est, 1.0, R, Vec3(1, 2, 3)), eval::Alignment::kSE3);
  EXPECT_LT(se3.position_rmse_m, 1e-9);
  const Quat yaw(Eigen::AngleAxisd(-2.0, Vec3::UnitZ()));
  const auto py = eval::compareWithReference(est, transformed(est, 1.0, yaw, Vec3(1, 2, 3)), eval::Alignment::kPosYaw);
  EXPECT_LT(py.position_rmse_m, 1e-9);
  EXPECT_LT(py.rotation_rmse_deg, 1e-6);
}

// With noise on the reference (in its own units), evo's number is that noise, and the metres are
// it divided by the scale.
TEST(ReferenceComparison, ErrorsAreInTheReferencesUnitsAsEvoMeasuresThem) {
  const auto est = walk(400);
  auto ref = transformed(est, 4.0, Quat::Identity(), Vec3::Zero());
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.08);  // reference units
  for (auto& p : ref) p.p += Vec3(noise(rng), noise(rng), noise(rng));
  const auto c = eval::compareWithReference(est, ref, eval::Alignment::kSim3);
  EXPECT_NEAR(c.position_rmse_reference_units, 0.08 * std::sqrt(3.0), 0.01);
  EXPECT_NEAR(c.position_rmse_m * c.scale, c.position_rmse_reference_units, 1e-12);
  EXPECT_NEAR(c.scale, 4.0, 0.01);
}

// EuRoC's ground truth CSV (nanoseconds, position then qw qx qy qz) is a reference as it is.
TEST(ReferenceComparison, EurocGroundTruthCsvIsReadAsAReference) {
  const std::string path = vi_ekf_slam::test::programScratch() / "euroc_gt.csv";
  {
    std::ofstream f(path);
    f << "#timestamp,p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z [],v_RS_R_x [m s^-1],"
         "v_RS_R_y [m s^-1],v_RS_R_z [m s^-1],b_w_RS_S_x [rad s^-1],b_w_RS_S_y [rad s^-1],b_w_RS_S_z [rad s^-1],"
         "b_a_RS_S_x [m s^-2],b_a_RS_S_y [m s^-2],b_a_RS_S_z [m s^-2]\n";
    f << "1403715273262142976,0.878895,2.1834,0.948427,0.069433,-0.824237,-0.106942,-0.551702,0,0,0,0,0,0,0,0,0\n";
    f << "1403715273312143104,0.878973,2.18348,0.948329,0.0694375,-0.824253,-0.106951,-0.551676,0,0,0,0,0,0,0,0,0\n";
  }
  const auto poses = io::readTrajectoryFile(path);
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_NEAR(poses[0].t, 1403715273.262143, 1e-6);
  EXPECT_NEAR(poses[1].p.y(), 2.18348, 1e-12);
  EXPECT_NEAR(poses[0].q.w(), 0.069433, 1e-3);
  // A comma-separated TUM file stays a TUM file.
  std::ofstream(path) << "10.0,1,2,3,0,0,0,1\n10.1,1,2,3,0,0,0,1\n";
  EXPECT_EQ(io::readTrajectoryFile(path).size(), 2u);
}

// A start mapped at the wrong scale: the estimate's first 10 s are 0.7 of the truth's size, the rest
// is right. Each window is aligned on its own: the first shows 1/0.7 of the later windows' scale,
// which the whole run's alignment averages away.
TEST(ReferenceComparison, EachWindowIsAlignedOnItsOwnAndShowsItsScale) {
  const auto truth = walk(600);  // 30 s
  const Quat R(Eigen::AngleAxisd(0.7, Vec3(1.0, 0.3, -0.2).normalized()));
  const auto ref = transformed(truth, 4.0, R, Vec3(-1.0, 2.0, 0.5));
  auto est = truth;
  for (auto& p : est)
    if (p.t < truth.front().t + 10.0) p.p = 0.7 * p.p + Vec3(0.3, -0.2, 0.1);
  const auto windows = eval::compareInWindows(est, ref, eval::Alignment::kSim3, 10.0);
  ASSERT_EQ(windows.size(), 3u);
  EXPECT_NEAR(windows[0].from_t, truth.front().t, 1e-12);
  EXPECT_NEAR(windows[0].comparison.scale, 4.0 / 0.7, 1e-6);
  EXPECT_NEAR(windows[1].comparison.scale, 4.0, 1e-6);
  EXPECT_NEAR(windows[2].comparison.scale, 4.0, 1e-6);
  EXPECT_LT(windows[0].comparison.position_rmse_m, 1e-6);
  EXPECT_NEAR(eval::firstWindowScaleRatio(windows), 1.0 / 0.7, 1e-6);
  const auto whole = eval::compareWithReference(est, ref, eval::Alignment::kSim3);
  EXPECT_GT(whole.position_rmse_m, 0.01);  // one alignment cannot fit both sizes
  // An estimate with less than a window gives one window, and no ratio.
  const std::vector<io::StampedPose> short_est(est.begin(), est.begin() + 50);
  EXPECT_EQ(eval::compareInWindows(short_est, ref, eval::Alignment::kSim3, 10.0).size(), 1u);
  EXPECT_TRUE(
      std::isnan(eval::firstWindowScaleRatio(eval::compareInWindows(short_est, ref, eval::Alignment::kSim3, 10.0))));
}
