// filter_start.h: the states the filter starts from.
#include <gtest/gtest.h>

#include "test_helpers.h"
#include "vi_ekf_slam/core/filter_start.h"

using namespace vi_ekf_slam;

TEST(FilterStart, AnEmptyStateCarriesTheCalibrationAndItsLayout) {
  EkfSlamConfig cfg;
  cfg.estimate_extrinsic = true;
  const CameraExtrinsics T = sim::torsoCameraExtrinsics();
  for (Mechanization m :
       {Mechanization::kWorldCentric, Mechanization::kSensorCentric, Mechanization::kSensorCentricComposition}) {
    const FilterState s = emptyState(cfg, T, m);
    EXPECT_EQ(s.mechanization(), m);
    EXPECT_TRUE(s.estimatesExtrinsic());
    EXPECT_EQ(s.x.T_b_c.p_b_c, T.p_b_c);
    EXPECT_EQ(s.x.T_b_c.R_b_c, T.R_b_c);
    EXPECT_EQ(s.numLandmarks(), 0);
  }
}

TEST(FilterStart, TheStartingCovarianceIsTheInitializersUncertainty) {
  EkfSlamConfig cfg;
  cfg.estimate_extrinsic = true;
  NavState init;
  init.timestamp = 12.5;
  init.p_n_b = Vec3(1, 2, 3);
  init.v_n_b = Vec3(1.2, 0, 0);
  InitialUncertainty u = cfg.initial;
  u.position_m = 0.1;
  u.velocity_mps = 0.2;
  u.yaw_rad = 0.3;
  u.roll_pitch_rad = 0.01;
  const FilterState s = startingState(cfg, sim::torsoCameraExtrinsics(), init, u, 0.02);
  EXPECT_EQ(s.mechanization(), Mechanization::kWorldCentric);
  EXPECT_EQ(s.timestamp, 12.5);
  EXPECT_EQ(s.x.p_s_b, init.p_n_b);
  EXPECT_EQ(s.x.t_d, 0.02);
  const Eigen::MatrixXd& P = s.covariance();
  EXPECT_DOUBLE_EQ(P(idx::kP, idx::kP), 0.01);
  EXPECT_DOUBLE_EQ(P(idx::kV + 1, idx::kV + 1), 0.04);
  EXPECT_DOUBLE_EQ(P(idx::kPsi, idx::kPsi), 1e-4);
  EXPECT_DOUBLE_EQ(P(idx::kPsi + 2, idx::kPsi + 2), 0.09);
  const int e = s.extrinsicIndex();
  EXPECT_DOUBLE_EQ(P(e, e), u.extrinsic_translation_m * u.extrinsic_translation_m);
  EXPECT_DOUBLE_EQ(P(idx::kV, idx::kPsi + 2), 0.0);  // independent unless the initializer says so
  // Without a time offset given, the configured one.
  EXPECT_EQ(startingState(cfg, sim::torsoCameraExtrinsics(), init, u, std::nullopt).x.t_d, cfg.camera_time_offset_s);
  // Known relative to its own heading: the velocity error gains e_z x v times the yaw error.
  u.velocity_relative_to_heading = true;
  const FilterState h = startingState(cfg, sim::torsoCameraExtrinsics(), init, u, std::nullopt);
  EXPECT_NEAR(h.covariance()(idx::kV + 1, idx::kPsi + 2), 1.2 * 0.09, 1e-12);
  EXPECT_NEAR(h.covariance()(idx::kV, idx::kPsi + 2), 0.0, 1e-15);
}
