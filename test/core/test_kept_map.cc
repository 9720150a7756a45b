// The map kept across runs (map_reuse/kept_map.h): its file round trip and refusals, the relocalization
// that places a filter's world in it (a known yaw and translation recovered from projections with
// outliers; a tilted or sparse match refused), and EkfSlam::moveWorld, which moves every
// navigation-frame quantity and its covariance with the world in every mechanization.
#include <gtest/gtest.h>

#include "scratch_dir.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include "test_helpers.h"
#include "vi_ekf_slam/core/ekf_slam.h"
#include "vi_ekf_slam/core/map_reuse/kept_map.h"
#include "vi_ekf_slam/core/map_reuse/relocalization.h"
#include "vi_ekf_slam/sim/sim_runner.h"

namespace vi_ekf_slam {
namespace {

Descriptor randomDescriptor(std::mt19937_64& rng) {
  Descriptor d;
  for (auto& b : d) b = static_cast<std::uint8_t>(rng() & 0xff);
  return d;
}

std::vector<MapPoint> randomPoints(int n, std::mt19937_64& rng) {
  std::vector<MapPoint> pts;
  for (int i = 0; i < n; ++i) {
    MapPoint p;
    p.id = 1000 + i;
    p.p_m = test::randomVec(rng, 4.0);
    p.cov = test::randomSpd(3, rng, 0.01);
    p.descriptor = randomDescriptor(rng);
    pts.push_back(p);
  }
  return pts;
}

std::string tempPath(const std::string& name) { return test::programScratch() / name; }

Eigen::Isometry3d pose(const Mat3& R, const Vec3& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = p;
  return T;
}

/// A camera view of a map: points 2-8 m in front of the camera at T_m_b, their projections (with
/// noise) as features carrying the points' descriptors, and `outliers` features whose descriptors
/// are map points' but whose pixels are elsewhere.
struct View {
  KeptMap map;
  std::vector<FeatureObservation> features;
};
View viewOf(const Eigen::Isometry3d& T_m_b, const CameraModel& cam, const CameraExtrinsics& T_b_c, int points,
            int outliers, std::mt19937_64& rng) {
  View v;
  const Eigen::Isometry3d T_m_c = T_m_b * pose(T_b_c.R_b_c, T_b_c.p_b_c);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> px(0.0, 0.5);
  std::vector<MapPoint> pts;
  while (static_cast<int>(pts.size()) < points) {
    const Vec3 p_c((u(rng) - 0.5) * 6.0, (u(rng) - 0.5) * 4.0, 2.0 + 6.0 * u(rng));
    Eigen::Vector2d uv;
    if (!cam.project(p_c, &uv) || !cam.inImage(uv, 5.0)) continue;
    MapPoint m;
    m.id = 500 + static_cast<std::int64_t>(pts.size());
    m.p_m = T_m_c * p_c;
    m.cov = 1e-4 * Mat3::Identity();
    m.descriptor = randomDescriptor(rng);
    pts.push_back(m);
    v.features.push_back({m.id + 10000, uv + Eigen::Vector2d(px(rng), px(rng)), m.descriptor});
  }
  for (int k = 0; k < outliers; ++k) {
    FeatureObservation& f = v.features[static_cast<size_t>(k)];
    f.uv = Eigen::Vector2d(u(rng) * cam.width(), u(rng) * cam.height());
  }
  v.map.merge(pts);
  return v;
}

}  // namespace

TEST(KeptMap, SavesAndLoadsEveryValueOfItsPoints) {
  std::mt19937_64 rng(3);
  KeptMap a;
  a.merge(randomPoints(40, rng));
  for (const char* ext : {".yaml", ".json", ".yaml.gz"}) {
    const std::string path = tempPath(std::string("vi_ekf_slam_map_test") + ext);
    std::string err;
    ASSERT_TRUE(a.save(path, &err)) << err;
    KeptMap b;
    ASSERT_TRUE(b.load(path, &err)) << err;
    ASSERT_EQ(b.size(), a.size()) << ext;
    for (int i = 0; i < a.size(); ++i) {
      const MapPoint &p = a.points()[static_cast<size_t>(i)], &q = b.points()[static_cast<size_t>(i)];
      EXPECT_EQ(p.id, q.id);
      EXPECT_LT((p.p_m - q.p_m).norm(), 1e-12);
      EXPECT_LT((p.cov - q.cov).norm(), 1e-12);
      EXPECT_EQ(p.descriptor, q.descriptor);
    }
    std::remove(path.c_str());
  }
}

TEST(KeptMap, RefusesAFileThatIsNotAMapAndKeepsItsPoints) {
  std::mt19937_64 rng(4);
  KeptMap a;
  a.merge(randomPoints(5, rng));
  std::string err;
  EXPECT_FALSE(a.load(tempPath("vi_ekf_slam_no_such_map.yaml"), &err));
  EXPECT_NE(err.find("vi_ekf_slam_no_such_map.yaml"), std::string::npos);
  const std::string other = tempPath("vi_ekf_slam_not_a_map.yaml");
  std::ofstream(other) << "%YAML:1.0\n---\nformat: \"something else\"\n";
  EXPECT_FALSE(a.load(other, &err));
  EXPECT_NE(err.find("not a vi_ekf_slam map"), std::string::npos);
  const std::string truncated = tempPath("vi_ekf_slam_truncated_map.yaml");
  std::ofstream(truncated) << "%YAML:1.0\n---\nformat: \"vi_ekf_slam map\"\nversion: 1\npoints: 3\n";
  EXPECT_FALSE(a.load(truncated, &err));
  EXPECT_EQ(a.size(), 5);
  std::remove(other.c_str());
  std::remove(truncated.c_str());
}

TEST(KeptMap, APointMappedAgainReplacesItsOldSelfAndTheOldestLeaveFirst) {
  std::mt19937_64 rng(5);
  KeptMap a(10);
  std::vector<MapPoint> first = randomPoints(8, rng);
  a.merge(first);
  std::vector<MapPoint> again = {first[2]};
  again[0].p_m += Vec3(1.0, 0.0, 0.0);
  a.merge(again);
  EXPECT_EQ(a.size(), 8);
  EXPECT_LT((a.points().back().p_m - again[0].p_m).norm(), 1e-12);
  std::vector<MapPoint> more = randomPoints(8, rng);
  for (auto& p : more) p.id += 100;
  a.merge(more);
  EXPECT_EQ(a.size(), 10);
  EXPECT_EQ(a.points().front().id, first[7].id);  // the 6 archived first (but the re-mapped one) left
}

TEST(Relocalization, RecoversTheYawAndTranslationBetweenTheWorlds) {
  std::mt19937_64 rng(6);
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T_b_c = test::forwardCamera();
  // The body in the map, and the filter's world {n} placed 35 deg and some metres away.
  const Eigen::Isometry3d T_m_b = pose(expSO3(Vec3(0.05, -0.03, 1.2)), Vec3(3.0, -2.0, 1.4));
  const Eigen::Isometry3d T_m_n_true =
      pose(Eigen::AngleAxisd(0.61, Vec3::UnitZ()).toRotationMatrix(), Vec3(-4, 7, 0.3));
  const Eigen::Isometry3d T_n_b = T_m_n_true.inverse() * T_m_b;
  const View v = viewOf(T_m_b, cam, T_b_c, 60, 15, rng);
  MapReuseParams params;
  std::string why;
  const auto r = relocalize(v.map, v.features, cam, T_b_c, T_n_b, params, &why);
  ASSERT_TRUE(r) << why;
  EXPECT_LT((r->T_m_n.translation() - T_m_n_true.translation()).norm(), 0.03);
  EXPECT_LT(logSO3(r->T_m_n.linear() * T_m_n_true.linear().transpose()).norm(), 0.2 * M_PI / 180.0);
  EXPECT_GE(r->inliers, 40);
  EXPECT_LE(r->inliers, 45);  // the 15 moved features are not among them
  for (const auto& pair : r->pairs) EXPECT_EQ(pair.feature_id, pair.point_id + 10000);
  EXPECT_LT(r->tilt_deg, 0.5);
}

TEST(Relocalization, RefusesATiltedWorldAndTooFewMatches) {
  std::mt19937_64 rng(7);
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T_b_c = test::forwardCamera();
  const Eigen::Isometry3d T_m_b = pose(expSO3(Vec3(0.0, 0.0, 0.4)), Vec3(1.0, 1.0, 1.4));
  const View v = viewOf(T_m_b, cam, T_b_c, 40, 0, rng);
  MapReuseParams params;
  std::string why;
  // The filter's gravity 10 deg off the map's: no gravity-aligned world explains the view.
  const Eigen::Isometry3d tilted = pose(expSO3(Vec3(0.17, 0.0, 0.0)), Vec3::Zero()) * T_m_b;
  EXPECT_FALSE(relocalize(v.map, v.features, cam, T_b_c, tilted, params, &why));
  EXPECT_NE(why.find("tilted"), std::string::npos) << why;
  // Fewer agreeing matches than relocalize_min_inliers.
  const std::vector<FeatureObservation> few(v.features.begin(), v.features.begin() + 8);
  EXPECT_FALSE(relocalize(v.map, few, cam, T_b_c, T_m_b, params, &why));
  // Look-alikes: two map points with one descriptor fail the ratio test, so none is matched.
  KeptMap twins = v.map;
  std::vector<MapPoint> copies = twins.points();
  for (auto& p : copies) {
    p.id += 5000;
    p.p_m += Vec3(0.5, 0.0, 0.0);
  }
  twins.merge(copies);
  EXPECT_FALSE(relocalize(twins, v.features, cam, T_b_c, T_m_b, params, &why));
  EXPECT_NE(why.find("appearance matches"), std::string::npos) << why;
}

class MoveWorld : public ::testing::TestWithParam<Mechanization> {};

TEST_P(MoveWorld, MovesEveryNavigationQuantityAndItsCovariance) {
  const sim::Scenario sc = sim::circleScenario(3.0, true, 2);
  EkfSlamConfig cfg;
  cfg.mechanization = GetParam();
  cfg.imu_noise = sc.imu.noise;
  std::mt19937_64 rng(29);
  const Eigen::Isometry3d T = pose(Eigen::AngleAxisd(-1.1, Vec3::UnitZ()).toRotationMatrix(), Vec3(2.0, -5.0, 0.7));
  int moved = 0;
  sim::runSimulation(sc, cfg, sim::trueNavState(*sc.trajectory, 0.0), rng, [&](EkfSlam& filter, sim::FrameRecord& rec) {
    if (!rec.result.processed || moved > 0 || rec.t < 1.5) return;
    const NavState a = filter.navState();
    const std::vector<NavLandmark> la = filter.landmarks();
    filter.moveWorld(T);
    ++moved;
    const NavState b = filter.navState();
    const Mat3 R = T.linear();
    EXPECT_EQ(filter.mechanization(), GetParam());
    EXPECT_LT((b.p_n_b - T * a.p_n_b).norm(), 1e-9);
    EXPECT_LT((b.v_n_b - R * a.v_n_b).norm(), 1e-9);
    EXPECT_LT(rotationError(b.q_n_b, Quat(R) * a.q_n_b).norm(), 1e-9);
    EXPECT_LT((b.b_a - a.b_a).norm(), 1e-12);
    // [p, v, b_a, psi, b_g]: positions, velocities and global attitude errors turn with R.
    Eigen::Matrix<double, idx::kNavDim, idx::kNavDim> G = Eigen::Matrix<double, idx::kNavDim, idx::kNavDim>::Identity();
    for (int blk : {idx::kP, idx::kV, idx::kPsi}) G.block<3, 3>(blk, blk) = R;
    EXPECT_LT(test::maxAbs(b.cov - G * a.cov * G.transpose()), 1e-9);
    const std::vector<NavLandmark> lb = filter.landmarks();
    ASSERT_EQ(la.size(), lb.size());
    for (size_t i = 0; i < la.size(); ++i) {
      EXPECT_LT((lb[i].p_n_l - T * la[i].p_n_l).norm(), 1e-9);
      EXPECT_LT(test::maxAbs(lb[i].cov - R * la[i].cov * R.transpose()), 1e-9);
    }
  });
  EXPECT_EQ(moved, 1);
}

INSTANTIATE_TEST_SUITE_P(Mechanizations, MoveWorld,
                         ::testing::Values(Mechanization::kWorldCentric, Mechanization::kSensorCentric,
                                           Mechanization::kSensorCentricComposition));

}  // namespace vi_ekf_slam
