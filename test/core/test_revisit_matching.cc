// Keeping the map: the search region of a landmark whose track ended, and the appearance match
// that may re-identify it, only where nothing else in the image looks like it (map_reuse/revisit_matching.h).
#include <gtest/gtest.h>

#include "test_helpers.h"
#include "vi_ekf_slam/core/chi_squared.h"
#include "vi_ekf_slam/core/ekf_update.h"
#include "vi_ekf_slam/core/map_reuse/revisit_matching.h"

using namespace vi_ekf_slam;

namespace {
Descriptor pattern(std::uint8_t seed) {
  Descriptor d;
  for (size_t i = 0; i < d.size(); ++i) d[i] = static_cast<std::uint8_t>(seed * 37 + i * 101 + (i * i) % 7);
  return d;
}
/// d with its first `bits` bits flipped.
Descriptor flipped(Descriptor d, int bits) {
  for (int b = 0; b < bits; ++b) d[static_cast<size_t>(b / 8)] ^= static_cast<std::uint8_t>(1u << (b % 8));
  return d;
}
RevisitCandidate candidate(std::int64_t id, const Eigen::Vector2d& uv, double sigma_px, const Descriptor& d) {
  return {id, uv, sigma_px * sigma_px * Eigen::Matrix2d::Identity(), d};
}
FeatureObservation corner(std::int64_t id, const Eigen::Vector2d& uv, const Descriptor& d) { return {id, uv, d}; }
}  // namespace

TEST(RevisitMatching, HammingDistanceCountsTheDifferingBits) {
  const Descriptor a = pattern(1);
  EXPECT_EQ(hammingDistance(a, a), 0);
  EXPECT_EQ(hammingDistance(a, flipped(a, 13)), 13);
  Descriptor inverse = a;
  for (auto& byte : inverse) byte = static_cast<std::uint8_t>(~byte);
  EXPECT_EQ(hammingDistance(a, inverse), 256);
}

TEST(RevisitMatching, AMatchIsTheLookAlikeInsideTheRegion) {
  const MapReuseParams p;
  const Descriptor a = pattern(1), b = pattern(2);
  ASSERT_GT(hammingDistance(a, b), 80);
  const std::vector<RevisitCandidate> lm = {candidate(7, {100, 100}, 5.0, a)};
  // The look-alike 8 px away (1.6 sigma) is taken; an unlike corner nearer is not.
  auto m = matchRevisits(lm, {corner(1, {103, 100}, b), corner(2, {108, 100}, flipped(a, 20))}, p);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].track_id, 2);
  EXPECT_EQ(m[0].landmark_id, 7);
  EXPECT_EQ(m[0].distance, 20);
  // The same look-alike 20 px away (4 sigma) is outside the region: nothing.
  EXPECT_TRUE(matchRevisits(lm, {corner(2, {120, 100}, flipped(a, 20))}, p).empty());
  // Inside the region but too different: nothing.
  EXPECT_TRUE(matchRevisits(lm, {corner(2, {101, 100}, flipped(a, p.max_descriptor_distance + 1))}, p).empty());
  // A corner without a descriptor cannot match.
  EXPECT_TRUE(matchRevisits(lm, {FeatureObservation{2, {100, 100}, std::nullopt}}, p).empty());
}

TEST(RevisitMatching, TwoLookAlikesInOneRegionMatchNeither) {
  // Repeated texture: two corners that both look like the landmark (the ratio test on the
  // landmark's side), or two landmarks that look like one corner (on the corner's side).
  const MapReuseParams p;
  const Descriptor a = pattern(3);
  const std::vector<RevisitCandidate> one = {candidate(7, {100, 100}, 5.0, a)};
  EXPECT_TRUE(
      matchRevisits(one, {corner(1, {98, 100}, flipped(a, 10)), corner(2, {102, 100}, flipped(a, 11))}, p).empty());
  const std::vector<RevisitCandidate> two = {candidate(7, {100, 100}, 5.0, a), candidate(8, {104, 100}, 5.0, a)};
  EXPECT_TRUE(matchRevisits(two, {corner(1, {102, 100}, flipped(a, 10))}, p).empty());
  // The same two landmarks far enough apart that each region holds only its own corner: still
  // neither, each corner looks like the other landmark too (the texture repeats in view, and a
  // region's one look-alike may be another point while the landmark itself went undetected).
  const std::vector<RevisitCandidate> apart = {candidate(7, {100, 100}, 5.0, a), candidate(8, {200, 100}, 5.0, a)};
  const std::vector<FeatureObservation> far_corners = {corner(1, {101, 100}, flipped(a, 10)),
                                                       corner(2, {199, 100}, flipped(a, 12))};
  EXPECT_TRUE(matchRevisits(apart, far_corners, p).empty());
  MapReuseParams in_region = p;  // (the ratio test over the regions only: both match)
  in_region.distinct_in_view = false;
  EXPECT_EQ(matchRevisits(apart, far_corners, in_region).size(), 2u);
  // So does a look-alike among the image's other features (a track's appearance).
  EXPECT_TRUE(
      matchRevisits(one, {corner(1, {101, 100}, flipped(a, 10))}, p, {corner(5, {300, 50}, flipped(a, 12))}).empty());
  EXPECT_EQ(matchRevisits(one, {corner(1, {101, 100}, flipped(a, 10))}, p, {corner(5, {300, 50}, pattern(9))}).size(),
            1u);
  // Two landmarks that look different, each in its own region: both match.
  const Descriptor b = pattern(5);
  ASSERT_GT(hammingDistance(a, b), 80);
  const std::vector<RevisitCandidate> unlike = {candidate(7, {100, 100}, 5.0, a), candidate(8, {200, 100}, 5.0, b)};
  const auto m =
      matchRevisits(unlike, {corner(1, {101, 100}, flipped(a, 10)), corner(2, {199, 100}, flipped(b, 12))}, p);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0].landmark_id, 7);
  EXPECT_EQ(m[0].track_id, 1);
  EXPECT_EQ(m[1].landmark_id, 8);
  EXPECT_EQ(m[1].track_id, 2);
  // A clearly better look-alike beside a poor one passes the ratio test.
  const auto best = matchRevisits(one, {corner(1, {98, 100}, flipped(a, 5)), corner(2, {102, 100}, flipped(a, 45))}, p);
  ASSERT_EQ(best.size(), 1u);
  EXPECT_EQ(best[0].track_id, 1);
}

TEST(RevisitMatching, ALandmarkKnownTooLooselyIsNotSearchedFor) {
  MapReuseParams p;
  const Descriptor a = pattern(4);
  const std::vector<RevisitCandidate> wide = {candidate(7, {100, 100}, p.max_search_sigma_px * 1.1, a)};
  EXPECT_TRUE(matchRevisits(wide, {corner(1, {100, 100}, a)}, p).empty());
  p.max_search_sigma_px *= 1.2;
  EXPECT_EQ(matchRevisits(wide, {corner(1, {100, 100}, a)}, p).size(), 1u);
}

TEST(RevisitMatching, TheSearchRegionIsTheUpdatesInnovationCovariance) {
  // predictWithCovariance gives h(x) and S = H P H^T + R with the update's own Jacobian: the
  // normalized innovation of an observation at uv + e is e^T S^-1 e, as the update gates it.
  std::mt19937_64 rng(21);
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  const FilterState s = test::randomState(Mechanization::kSensorCentricComposition, 6, rng);
  UpdateParams params;
  params.pixel_noise_px = 1.5;
  int checked = 0;
  for (int i = 0; i < s.numLandmarks(); ++i) {
    Eigen::Vector2d uv;
    ObservationJacobians J;
    const auto pred = predictWithCovariance(s, i, cam, T, params);
    if (!predictObservation(s.x, s.landmark(i), cam, T, &uv, &J) || !cam.inImage(uv, 0.0)) {
      EXPECT_FALSE(pred.has_value());
      continue;
    }
    ASSERT_TRUE(pred.has_value());
    EXPECT_LT((pred->uv - uv).norm(), 1e-9);
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(2, s.dim());
    H.middleCols<3>(idx::kP) = J.H_p;
    H.middleCols<3>(idx::kPsi) = J.H_psi;
    H.middleCols<3>(s.landmarkIndex(i)) = J.H_l;
    Eigen::Vector2d H_td;
    ASSERT_TRUE(predictImageVelocity(s.x, s.landmark(i), cam, T, Vec3::Zero(), &H_td));
    H.col(idx::kTd) = H_td;
    const Eigen::Matrix2d S = H * s.covariance() * H.transpose() + 2.25 * Eigen::Matrix2d::Identity();
    EXPECT_LT(test::maxAbs(pred->S - S), 1e-9 * S.norm());
    ++checked;
  }
  EXPECT_GT(checked, 0);
}

TEST(RevisitMatching, APendingMatchAgreesWhileItsTrackStaysOnThePrediction) {
  // A match is believed only after its track has gone on landing where the landmark is predicted
  // (revisit_confirm_frames). S: a 1.5 px prediction, 1 px pixel noise, the update's 0.95 gate.
  const MapReuseParams p;
  const Eigen::Matrix2d S = 1.5 * 1.5 * Eigen::Matrix2d::Identity();
  const Eigen::Vector2d first(2.0, -1.5);  // the filter's error of the moment: 1.7 sigma
  // The true point keeps that error, with pixel noise: it agrees.
  EXPECT_TRUE(pendingRevisitAgrees(first + Eigen::Vector2d(0.8, 0.6), S, first, 0.95, 1.0, p));
  // A look-alike at another depth drifts off: 4.5 px from where it was matched, though still
  // inside the update's gate: refused by its drift.
  const Eigen::Vector2d drifted(-2.5, -1.5);
  ASSERT_LT(drifted.squaredNorm() / S(0, 0), chiSquaredQuantile(0.95, 2.0));
  EXPECT_FALSE(pendingRevisitAgrees(drifted, S, first, 0.95, 1.0, p));
  // A track that stays put but outside the update's gate is refused too.
  EXPECT_FALSE(pendingRevisitAgrees(Eigen::Vector2d(4.0, 1.0), S, Eigen::Vector2d(4.0, 1.0), 0.95, 1.0, p));
  // A wider gate (the outlier watch's clean gate) takes that offset; the drift bound does not move.
  EXPECT_TRUE(pendingRevisitAgrees(Eigen::Vector2d(4.0, 1.0), S, Eigen::Vector2d(4.0, 1.0), 0.9999, 1.0, p));
  EXPECT_FALSE(pendingRevisitAgrees(drifted, S, first, 0.9999, 1.0, p));
  // A degenerate prediction or a non-finite pixel never agrees.
  EXPECT_FALSE(pendingRevisitAgrees(first, Eigen::Matrix2d::Zero(), first, 0.95, 1.0, p));
  EXPECT_FALSE(pendingRevisitAgrees(Eigen::Vector2d(NAN, 0.0), S, first, 0.95, 1.0, p));
}
