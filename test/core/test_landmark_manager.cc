// LandmarkManager: which tracks enter the map and which leave, on a filter state of its own.
#include <gtest/gtest.h>

#include "test_helpers.h"
#include "vi_ekf_slam/core/filter_start.h"
#include "vi_ekf_slam/core/landmark_manager.h"

using namespace vi_ekf_slam;

namespace {

std::vector<FeatureObservation> tracks(std::int64_t first, int n) {
  std::vector<FeatureObservation> out;
  for (int i = 0; i < n; ++i) out.push_back({first + i, Eigen::Vector2d(100 + 40 * i, 200 + 10 * i)});
  return out;
}

}  // namespace

TEST(LandmarkManager, TheMapIsBoundedAndLandmarksNotSeenForTheTimeoutLeave) {
  EkfSlamConfig cfg;
  cfg.max_landmarks = 5;
  cfg.landmark_timeout_s = 0.1;
  cfg.mechanization = Mechanization::kSensorCentric;  // no delayed entry
  const CameraModel camera = sim::paperCamera();
  FilterState s = emptyState(cfg, sim::torsoCameraExtrinsics(), cfg.mechanization);
  LandmarkManager m;
  WithinRunMap map;
  m.started(s, 0.0);
  std::vector<std::int64_t> removed;
  const FilterView f{s, camera, cfg};
  EXPECT_EQ(m.addNow(f, map, tracks(0, 8), 0.0, &removed).size(), 5u);  // the bound
  EXPECT_TRUE(removed.empty());
  EXPECT_EQ(s.numLandmarks(), 5);
  // Seen at 0.05 s: landmarks 0 and 1 stay, the others time out at 0.2 s.
  m.seen(0, 0.15);
  m.seen(1, 0.15);
  EXPECT_EQ(m.addNow(f, map, tracks(100, 1), 0.2, &removed).size(), 1u);
  EXPECT_EQ(removed.size(), 3u);
  EXPECT_EQ(s.numLandmarks(), 3);
  EXPECT_TRUE(s.findLandmark(0) && s.findLandmark(1) && s.findLandmark(100));
  // A full map makes room by the longest unseen, never one seen at this time (100).
  EXPECT_EQ(m.addNow(f, map, tracks(200, 4), 0.2, &removed).size(), 4u);
  EXPECT_EQ(removed, std::vector<std::int64_t>({0, 1}));
  EXPECT_EQ(s.numLandmarks(), 5);
  EXPECT_TRUE(s.findLandmark(100));
  m.remove(f, map, {100, 200});
  EXPECT_EQ(s.numLandmarks(), 3);
  EXPECT_FALSE(s.findLandmark(100));
}

TEST(LandmarkManager, WithDormantConsiderAPointLeavingTheTrackedMapIsAConsiderStateUntilSeenAgain) {
  for (bool consider : {true, false}) {
    EkfSlamConfig cfg;
    cfg.landmark_timeout_s = 0.1;
    cfg.mechanization = Mechanization::kSensorCentric;  // no delayed entry
    cfg.map.within_run = true;
    cfg.map.dormant_consider = consider;
    const CameraModel camera = sim::paperCamera();
    FilterState s = emptyState(cfg, sim::torsoCameraExtrinsics(), cfg.mechanization);
    LandmarkManager m;
    WithinRunMap map;
    m.started(s, 0.0);
    std::vector<std::int64_t> removed;
    const FilterView f{s, camera, cfg};
    std::vector<FeatureObservation> obs = tracks(0, 3);
    for (auto& o : obs) o.descriptor = Descriptor{};
    ASSERT_EQ(m.addNow(f, map, obs, 0.0, &removed).size(), 3u);
    map.rememberAppearance(s, obs);
    s.mutableCovariance() *= 1e-6;  // well mapped: a point the map keeps
    m.seen(0, 0.15);
    // 1 and 2 time out at 0.2 s and stay as dormant points.
    m.addNow(f, map, tracks(100, 1), 0.2, &removed);
    EXPECT_TRUE(removed.empty());
    EXPECT_EQ(map.dormantCount(), 2);
    for (std::int64_t id : {0, 1, 2}) EXPECT_EQ(s.landmark(*s.findLandmark(id)).consider, consider && id != 0);
    EXPECT_EQ(s.considerEntries().size(), consider ? 6u : 0u);
    map.observed(s, 1);  // seen again: an ordinary point from now on
    EXPECT_FALSE(s.landmark(*s.findLandmark(1)).consider);
    EXPECT_EQ(map.dormantCount(), 1);
  }
}

TEST(LandmarkManager, NewTracksWaitForABaselineOnlyWithInverseDepthComposedAfterEveryUpdate) {
  EkfSlamConfig cfg;
  cfg.mechanization = Mechanization::kSensorCentricComposition;
  cfg.composition_trigger = CompositionTrigger::kEveryUpdate;
  cfg.landmark_init = LandmarkInitMethod::kInverseDepth;
  const FilterState composed = emptyState(cfg, sim::torsoCameraExtrinsics(), cfg.mechanization);
  EXPECT_EQ(LandmarkManager::triangulationActive(composed, cfg), cfg.triangulation.enabled);
  cfg.triangulation.enabled = true;
  EXPECT_TRUE(LandmarkManager::triangulationActive(composed, cfg));
  EkfSlamConfig other = cfg;
  other.landmark_init = LandmarkInitMethod::kFixedDepth;
  EXPECT_FALSE(LandmarkManager::triangulationActive(composed, other));
  other = cfg;
  other.composition_trigger = CompositionTrigger::kNever;
  EXPECT_FALSE(LandmarkManager::triangulationActive(composed, other));
  EXPECT_FALSE(LandmarkManager::triangulationActive(
      emptyState(cfg, sim::torsoCameraExtrinsics(), Mechanization::kWorldCentric), cfg));
}

TEST(LandmarkManager, NewLandmarksStartAtTheSceneDepthAStartSawUntilTheMapKnowsItsOwn) {
  EkfSlamConfig cfg;
  cfg.inverse_depth_scene_prior = true;
  FilterState s = emptyState(cfg, sim::torsoCameraExtrinsics(), cfg.mechanization);
  LandmarkManager m;
  m.started(s, 0.0);
  EXPECT_EQ(m.newLandmarkDepth(s, cfg), cfg.inverse_depth_initial_m);
  m.started(s, 7.5);  // a moving start saw the scene at 7.5 m
  EXPECT_EQ(m.newLandmarkDepth(s, cfg), 7.5);
  cfg.inverse_depth_scene_prior = false;
  EXPECT_EQ(m.newLandmarkDepth(s, cfg), cfg.inverse_depth_initial_m);
}
