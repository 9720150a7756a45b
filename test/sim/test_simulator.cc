#include <gtest/gtest.h>

#include "scratch_dir.h"

#include <algorithm>
#include <fstream>
#include <set>

#include "test_helpers.h"
#include "vi_ekf_slam/core/ekf_slam.h"
#include "vi_ekf_slam/sim/bspline_trajectory.h"
#include "vi_ekf_slam/sim/camera_simulator.h"
#include "vi_ekf_slam/sim/hallway.h"
#include "vi_ekf_slam/sim/scenarios.h"
#include "vi_ekf_slam/sim/sim_runner.h"

using namespace vi_ekf_slam;

namespace {

/// Integrates the noise-free synthesized IMU with the filter's own strapdown (through EkfSlam's
/// buffer and interpolation) from the true start and returns the worst position and attitude
/// error against the trajectory over [t0, t1].
std::pair<double, double> deadReckoningError(const sim::Trajectory& traj, double t0, double t1) {
  sim::ImuSimParams p;
  p.noise_enabled = false;
  std::mt19937_64 rng(1);
  const sim::ImuSequence imu = sim::simulateImu(traj, p, rng);
  EkfSlam f(EkfSlamConfig(), sim::paperCamera(), sim::torsoCameraExtrinsics());
  f.initialize(sim::trueNavState(traj, t0));
  double max_p = 0.0, max_q = 0.0;
  double next = t0 + 0.5;
  for (const auto& sample : imu.samples) {
    f.addImu(sample);
    if (sample.timestamp < next || next > t1) continue;
    EXPECT_TRUE(f.propagateTo(next));
    const NavState n = f.navState();
    const sim::TrajectorySample s = traj.sample(next);
    max_p = std::max(max_p, (n.p_n_b - s.p_n_b).norm());
    max_q = std::max(max_q, rotationError(n.q_n_b, s.q_n_b).norm());
    next += 0.5;
  }
  EXPECT_GT(next, t1);
  return {max_p, max_q};
}

std::string writeTemp(const std::string& name, const std::string& content) {
  const std::string path = test::programScratch() / name;
  std::ofstream(path) << content;
  return path;
}

}  // namespace

// The IMU synthesized from the hallway walk (C2 B-spline with gait) integrates back to the walk.
TEST(Simulator, ImuIntegratesBackToTheHallwayWalk) {
  const sim::HallwayParams hp;
  const auto walk = sim::pedestrianWalk(hp);
  EXPECT_LE(walk->startTime(), 0.0);
  EXPECT_GE(walk->endTime(), hp.duration_s);
  const auto [p_err, q_err] = deadReckoningError(*walk, 0.0, 10.0);
  // Measured: 2.5 mm and 0.06 mrad after 10 s of pure inertial dead reckoning at 200 Hz.
  EXPECT_LT(p_err, 0.01);
  EXPECT_LT(q_err, 2e-4);
}

TEST(Simulator, ImuIntegratesBackToAnAnalyticTrajectory) {
  const sim::LissajousTrajectory traj(Vec3::Zero(), Vec3(0.3, 0.4, 0.2), Vec3(1.1, 0.8, 1.7), Vec3(0.1, 0.08, 0.15),
                                      Vec3(0.9, 1.3, 0.7), 20.0);
  const auto [p_err, q_err] = deadReckoningError(traj, 0.0, 20.0);
  EXPECT_LT(p_err, 1e-3);
  EXPECT_LT(q_err, 1e-5);
}

TEST(Simulator, HallwayWalkLooksLikeThePaper) {
  const sim::HallwayParams hp;
  const auto walk = sim::pedestrianWalk(hp);
  const sim::HallwayLayout lay = sim::hallwayLayout(hp);
  // ~1.3 m/s along the hallway, sharp 90 deg right turn at ~23 s, 35 s in all.
  EXPECT_NEAR(walk->sample(12.0).v_n_b.norm(), 1.3, 0.1);
  const double yaw_before = logQuat(walk->sample(21.5).q_n_b).z();
  const double yaw_after = logQuat(walk->sample(24.5).q_n_b).z();
  EXPECT_NEAR(yaw_after - yaw_before, M_PI / 2, 0.1);
  const sim::TrajectorySample at_turn = walk->sample(hp.turn_time_s);
  EXPECT_NEAR(at_turn.p_n_b.x(), lay.turn_x_m, 1.0);
  // Gait: vertical bounce of a few cm while walking, and the walk stays inside the corridors.
  double z_min = 1e9, z_max = -1e9;
  for (double t = 5.0; t < 15.0; t += 0.01) {
    z_min = std::min(z_min, walk->sample(t).p_n_b.z());
    z_max = std::max(z_max, walk->sample(t).p_n_b.z());
  }
  EXPECT_GT(z_max - z_min, 0.02);
  EXPECT_LT(z_max - z_min, 0.1);
  for (double t = 0.0; t <= hp.duration_s; t += 0.1) {
    const Vec3 p = walk->sample(t).p_n_b;
    const bool in_main = std::abs(p.y()) < 0.5 * hp.main_width_m - 0.3;
    const bool in_side = std::abs(p.x() - lay.turn_x_m) < 0.5 * hp.side_width_m - 0.2;
    EXPECT_TRUE(in_main || in_side) << "t=" << t << " p=" << p.transpose();
  }
}

TEST(Simulator, LandmarksLieOnTheHallwaySurfaces) {
  const sim::HallwayParams hp;
  const auto quads = sim::hallwayGeometry(hp);
  std::mt19937_64 rng(3);
  const sim::LandmarkWorld w = sim::landmarksOnQuads(quads, 1.0, rng);
  double area = 0.0;
  for (const auto& q : quads) area += q.area();
  EXPECT_NEAR(static_cast<double>(w.size()), area, 4.0 * std::sqrt(area));  // Poisson count
  for (const auto& l : w) {
    bool on_some = false;
    for (const auto& q : quads) {
      const Vec3 d = l.p_n - q.origin;
      const double a = d.dot(q.u), b = d.dot(q.v), h = d.dot(q.normal());
      on_some |= std::abs(h) < 1e-9 && a >= -1e-9 && a <= q.u_len + 1e-9 && b >= -1e-9 && b <= q.v_len + 1e-9;
    }
    EXPECT_TRUE(on_some);
  }
  // Every surface faces the walker: its normal points towards the nearest point of the walk.
  const auto walk = sim::pedestrianWalk(hp);
  for (const auto& q : quads) {
    const Vec3 centre = q.origin + 0.5 * q.u_len * q.u + 0.5 * q.v_len * q.v;
    Vec3 nearest = walk->sample(0.0).p_n_b;
    for (double t = 0.0; t <= hp.duration_s; t += 0.1) {
      const Vec3 p = walk->sample(t).p_n_b;
      if ((p - centre).norm() < (nearest - centre).norm()) nearest = p;
    }
    EXPECT_GT(q.normal().dot(nearest - centre), 0.0) << q.kind << " at " << centre.transpose();
  }
}

TEST(Simulator, ProjectionsMatchTheCameraModel) {
  const sim::Scenario sc = sim::hallwayScenario(sim::HallwayParams(), 1.0, 4);
  sim::CameraSimParams p;
  for (double t : {3.0, 23.0, 30.0}) {
    const sim::TrajectorySample s = sc.trajectory->sample(t);
    const auto vis = sim::visibleLandmarks(s, sc.world, sc.camera, sc.T_b_c, p);
    ASSERT_GT(vis.size(), 20u) << "t=" << t;
    for (const auto& o : vis) {
      // Independent chain: world -> camera with R_n_c = R_n_b R_b_c, p_n_c = p_n_b + R_n_b p_b_c.
      const Mat3 R_n_c = s.q_n_b.toRotationMatrix() * sc.T_b_c.R_b_c;
      const Vec3 p_n_c = s.p_n_b + s.q_n_b * sc.T_b_c.p_b_c;
      const Vec3 p_c = R_n_c.transpose() * (sc.world[static_cast<size_t>(o.id)].p_n - p_n_c);
      ASSERT_GT(p_c.z(), 0.0);
      const Eigen::Vector2d xd = sc.camera.distort(Eigen::Vector2d(p_c.x() / p_c.z(), p_c.y() / p_c.z()));
      const Eigen::Vector2d uv(sc.camera.intrinsics().fx * xd.x() + sc.camera.intrinsics().cx,
                               sc.camera.intrinsics().fy * xd.y() + sc.camera.intrinsics().cy);
      EXPECT_LT((uv - o.uv).norm(), 1e-9);
      EXPECT_TRUE(sc.camera.inImage(o.uv));
    }
  }
}

TEST(Simulator, TrackingCameraKeepsTracksAndAddsNoise) {
  const sim::Scenario sc = sim::hallwayScenario(sim::HallwayParams(), 1.0, 5);
  sim::TrackingCamera cam(sc.world, sc.camera, sc.T_b_c, sc.cam);
  std::mt19937_64 rng(6);
  const CameraFrame a = cam.observe(sc.trajectory->sample(5.0), &rng);
  const CameraFrame b = cam.observe(sc.trajectory->sample(5.0 + 1.0 / 28), &rng);
  ASSERT_EQ(static_cast<int>(a.features.size()), sc.cam.max_features);
  int kept = 0;
  for (const auto& f : b.features) {
    for (const auto& g : a.features) kept += f.id == g.id;
  }
  EXPECT_GT(kept, 35);  // most tracks continue from one frame to the next
  // Pixel noise: residuals against the noise-free projection have ~1 px std-dev.
  const auto exact =
      sim::visibleLandmarks(sc.trajectory->sample(5.0 + 1.0 / 28), sc.world, sc.camera, sc.T_b_c, sc.cam);
  double s2 = 0.0;
  int n = 0;
  for (const auto& f : b.features) {
    for (const auto& e : exact) {
      if (e.id == f.id) {
        s2 += (f.uv - e.uv).squaredNorm();
        n += 2;
      }
    }
  }
  EXPECT_NEAR(std::sqrt(s2 / n), 1.0, 0.3);
}

TEST(Simulator, SyntheticImuNoiseHasTheConfiguredDensity) {
  const sim::CircleTrajectory traj(5.0, 0.0, 0.0, 100.0);  // at rest
  sim::ImuSimParams p;
  p.noise.accel_noise_density = 0.004;
  p.noise.gyro_noise_density = 2e-4;
  p.noise.accel_random_walk = 0.0;
  p.noise.gyro_random_walk = 0.0;
  std::mt19937_64 rng(7);
  const sim::ImuSequence imu = sim::simulateImu(traj, p, rng);
  double sa = 0.0, sg = 0.0;
  for (const auto& s : imu.samples) {
    sa += (s.am - Vec3(0, 0, -9.81)).squaredNorm();
    sg += s.wm.squaredNorm();
  }
  const double n = 3.0 * static_cast<double>(imu.samples.size());
  // Per-sample std-dev = density * sqrt(rate).
  EXPECT_NEAR(std::sqrt(sa / n), 0.004 * std::sqrt(200.0), 0.002);
  EXPECT_NEAR(std::sqrt(sg / n), 2e-4 * std::sqrt(200.0), 1e-4);
}

TEST(BsplineTrajectory, ReproducesTheInputPosesAndIsConsistent) {
  // Poses of an analytic motion at 20 Hz -> spline; compare at the input times.
  const sim::LissajousTrajectory ref(Vec3(1, 2, 0), Vec3(0.8, 0.5, 0.1), Vec3(0.4, 0.3, 1.0), Vec3(0.2, 0.1, 0.6),
                                     Vec3(0.5, 0.7, 0.3), 30.0);
  std::vector<io::StampedPose> poses;
  for (double t = 0.0; t <= 30.0; t += 0.05) {
    const auto s = ref.sample(t);
    poses.push_back({t, s.p_n_b, s.q_n_b, std::nullopt});
  }
  const sim::BsplineTrajectory spline(poses, 0.05);
  double max_p = 0, max_q = 0, max_v = 0, max_a = 0, max_w = 0;
  for (const auto& p : poses) {
    if (p.t < spline.startTime() || p.t > spline.endTime()) continue;
    const auto s = spline.sample(p.t), r = ref.sample(p.t);
    max_p = std::max(max_p, (s.p_n_b - p.p).norm());
    max_q = std::max(max_q, rotationError(s.q_n_b, p.q).norm());
    max_v = std::max(max_v, (s.v_n_b - r.v_n_b).norm());
    max_a = std::max(max_a, (s.a_n_b - r.a_n_b).norm());
    max_w = std::max(max_w, (s.w_b - r.w_b).norm());
  }
  EXPECT_LT(max_p, 1e-3);  // approximating spline: error ~ dt^2 a / 6
  EXPECT_LT(max_q, 2e-4);
  EXPECT_LT(max_v, 5e-3);
  EXPECT_LT(max_a, 0.02);
  EXPECT_LT(max_w, 5e-3);
  // Its own derivatives are consistent: finite differences of pose match v, a, w.
  const double h = 1e-5;
  for (double t = 1.0; t < 29.0; t += 0.731) {
    const auto s = spline.sample(t), sp = spline.sample(t + h), sm = spline.sample(t - h);
    EXPECT_LT(((sp.p_n_b - sm.p_n_b) / (2 * h) - s.v_n_b).norm(), 1e-6);
    EXPECT_LT(((sp.v_n_b - sm.v_n_b) / (2 * h) - s.a_n_b).norm(), 1e-5);
    EXPECT_LT((logQuat(sm.q_n_b.conjugate() * sp.q_n_b) / (2 * h) - s.w_b).norm(), 1e-6);
  }
}

TEST(BsplineTrajectory, RealTumFileLoadsAsSmoothMotion) {
  const char* data = std::getenv("DATA_DIR");
  if (!data) GTEST_SKIP() << "DATA_DIR not set: skipping the real-trajectory check";
  const std::string path = std::string(data) + "/trajectories/tum_corridor1_512_16_okvis.txt";
  if (!std::ifstream(path)) GTEST_SKIP() << path << " not found";
  const auto traj = sim::loadTumTrajectory(path);
  EXPECT_GT(traj->endTime() - traj->startTime(), 250.0);
  // A walking person: accelerations and rates stay physical.
  for (double t = traj->startTime(); t < traj->endTime(); t += 0.5) {
    const auto s = traj->sample(t);
    EXPECT_LT(s.a_n_b.norm(), 30.0);
    EXPECT_LT(s.w_b.norm(), 10.0);
  }
}

TEST(BsplineTrajectory, ClearErrorsForBadFiles) {
  EXPECT_THROW(sim::loadTumTrajectory("/nonexistent/file.txt"), std::runtime_error);
  const std::string bad = writeTemp("bad.txt", "# t x y z qx qy qz qw\n0 0 0 0 0 0 0 1\n0.1 0 0 zero 0 0 0 1\n");
  try {
    sim::loadTumTrajectory(bad);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(":3:"), std::string::npos) << e.what();
  }
  const std::string cols = writeTemp("cols.txt", "0 0 0 0 0 0 1\n");
  EXPECT_THROW(sim::loadTumTrajectory(cols), std::runtime_error);
  const std::string back = writeTemp("back.txt", "1 0 0 0 0 0 0 1\n0.5 0 0 0 0 0 0 1\n");
  EXPECT_THROW(sim::loadTumTrajectory(back), std::runtime_error);
  const std::string shortf = writeTemp("short.txt", "0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 0 1\n0.2 0 0 0 0 0 0 1\n");
  try {
    sim::loadTumTrajectory(shortf);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("at least 4"), std::string::npos) << e.what();
  }
}

TEST(Simulator, TruncatedTrajectoryIsATimeWindowOfItsBase) {
  const auto walk = sim::pedestrianWalk(sim::HallwayParams());
  const sim::TruncatedTrajectory window(walk, 10.0, 20.0);
  EXPECT_DOUBLE_EQ(window.startTime(), 10.0);
  EXPECT_DOUBLE_EQ(window.endTime(), 20.0);
  for (double t : {10.0, 12.5, 20.0}) {
    EXPECT_LT((window.sample(t).p_n_b - walk->sample(t).p_n_b).norm(), 1e-12);
  }
  // Outside the window the motion holds at its ends; a window beyond the base is clamped to it.
  EXPECT_LT((window.sample(25.0).p_n_b - walk->sample(20.0).p_n_b).norm(), 1e-12);
  const sim::TruncatedTrajectory past(walk, walk->endTime() + 5.0, walk->endTime() + 9.0);
  EXPECT_DOUBLE_EQ(past.startTime(), walk->endTime());
  EXPECT_DOUBLE_EQ(past.endTime(), walk->endTime());
}

TEST(Simulator, ALandmarkTrackedAgainGetsANewTrackIdThatMapsBackToIt) {
  const sim::Scenario sc = sim::hallwayScenario(sim::HallwayParams(), 1.0, 5);
  sim::TrackingCamera cam(sc.world, sc.camera, sc.T_b_c, sc.cam);
  std::mt19937_64 rng(6);
  const sim::TrajectorySample looking = sc.trajectory->sample(5.0);
  sim::TrajectorySample away = looking;  // turned round: none of the first frame's points in view
  away.q_n_b = (looking.q_n_b * Quat(Eigen::AngleAxisd(M_PI, Vec3::UnitZ()))).normalized();
  const CameraFrame a = cam.observe(looking, &rng);
  const CameraFrame gone = cam.observe(away, &rng);
  const CameraFrame b = cam.observe(looking, &rng);
  ASSERT_EQ(a.features.size(), b.features.size());
  std::set<std::int64_t> ids_a, landmarks_a, ids_gone;
  for (const auto& f : a.features) {
    ids_a.insert(f.id);
    landmarks_a.insert(sim::landmarkOfTrack(f.id, sc.world).id);
  }
  for (const auto& f : gone.features) ids_gone.insert(f.id);
  const auto exact = sim::visibleLandmarks(looking, sc.world, sc.camera, sc.T_b_c, sc.cam);
  int again = 0;
  for (const auto& f : b.features) {
    EXPECT_EQ(ids_a.count(f.id), 0u) << "a track that ended was continued";
    EXPECT_EQ(ids_gone.count(f.id), 0u);
    again += static_cast<int>(landmarks_a.count(sim::landmarkOfTrack(f.id, sc.world).id));
    // The id maps back to the landmark that was projected.
    const auto it = std::find_if(exact.begin(), exact.end(), [&](const FeatureObservation& e) {
      return e.id == sim::landmarkOfTrack(f.id, sc.world).id;
    });
    ASSERT_NE(it, exact.end());
    EXPECT_LT((it->uv - f.uv).norm(), 6.0);  // 1 px noise
  }
  EXPECT_GT(again, 20);  // the same landmarks are found again, under new ids
}

// A covered lens: the tracker has nothing to follow, so no track goes on after it.
TEST(Simulator, LosingTheTracksStartsNewOnesWithNewIds) {
  const sim::Scenario sc = sim::hallwayScenario(sim::HallwayParams(), 1.0, 5);
  sim::TrackingCamera cam(sc.world, sc.camera, sc.T_b_c, sc.cam);
  std::mt19937_64 rng(7);
  const sim::TrajectorySample s = sc.trajectory->sample(5.0);
  const CameraFrame before = cam.observe(s, &rng);
  cam.loseTracks();
  const CameraFrame after = cam.observe(s, &rng);
  ASSERT_EQ(static_cast<int>(after.features.size()), sc.cam.max_features);
  for (const auto& f : after.features) {
    for (const auto& g : before.features) EXPECT_NE(f.id, g.id);
  }
}

// A dynamic start (its own heading) registered to the truth's heading: with no yaw error drawn, the
// registered attitude is the truth up to the start's tilt error, whatever the body's axes. It used
// to take each attitude's heading from its body x axis, which is near vertical on an IMU mounted x
// up (EuRoC's, UDel's): a 10 mrad tilt error then became a yaw error of up to 0.5 rad, and the
// simulated dynamic starts on those trajectories several times over their NEES band.
TEST(Simulator, RegistrationToTheTruthTurnsAboutTheVerticalForAnyBodyAxes) {
  std::mt19937_64 rng(9);
  InitialUncertainty u;
  u.yaw_rad = 0.0;
  u.position_m = 0.0;
  for (const Quat& mount : {Quat::Identity(), Quat(Eigen::AngleAxisd(-0.5 * M_PI, Vec3::UnitY()))}) {
    for (int i = 0; i < 10; ++i) {
      NavState truth;
      truth.q_n_b = (expQuat(test::randomVec(rng, 0.05)) * mount).normalized();
      truth.v_n_b = Vec3(1.2, -0.4, 0.1);
      truth.p_n_b = Vec3(3.0, 1.0, -1.5);
      const Vec3 tilt = test::randomVec(rng, 0.01).cwiseProduct(Vec3(1.0, 1.0, 0.0));
      const Quat heading(Eigen::AngleAxisd(std::uniform_real_distribution<double>(-3.0, 3.0)(rng), Vec3::UnitZ()));
      NavState aligned = truth;
      aligned.q_n_b = (heading * expQuat(tilt) * truth.q_n_b).normalized();
      aligned.v_n_b = heading * truth.v_n_b;
      aligned.p_n_b.setZero();
      const NavState r = sim::registerToTruth(aligned, truth, u, rng);
      EXPECT_LT(logQuat(r.q_n_b * truth.q_n_b.conjugate()).norm(), 2.0 * tilt.norm() + 1e-6);
      EXPECT_LT((r.v_n_b - truth.v_n_b).norm(), 2.0 * tilt.norm() * truth.v_n_b.norm() + 1e-6);
      EXPECT_LT((r.p_n_b - truth.p_n_b).norm(), 1e-12);
    }
  }
}
