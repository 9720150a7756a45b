#include "vi_ekf_slam/core/map_memory.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <bitset>
#include <limits>

#include "vi_ekf_slam/core/chi_squared.h"

namespace vi_ekf_slam {

int hammingDistance(const Descriptor& a, const Descriptor& b) {
  int d = 0;
  for (size_t i = 0; i < a.size(); ++i) d += static_cast<int>(std::bitset<8>(a[i] ^ b[i]).count());
  return d;
}

bool pendingRevisitAgrees(const Eigen::Vector2d& e, const Eigen::Matrix2d& S, const Eigen::Vector2d& first_e,
                          double gate_probability, double pixel_noise_px, const MapMemoryParams& params) {
  const Eigen::LLT<Eigen::Matrix2d> llt(S);  // (fails on a covariance that is not positive definite)
  if (llt.info() != Eigen::Success || !e.allFinite() || !first_e.allFinite()) return false;
  const double nis = e.dot(llt.solve(e));
  const double drift = (e - first_e).squaredNorm() / (2.0 * pixel_noise_px * pixel_noise_px);
  return nis <= chiSquaredQuantile(gate_probability, 2.0) &&
         drift <= chiSquaredQuantile(params.search_gate_probability, 2.0);
}

std::vector<RevisitMatch> matchRevisits(const std::vector<RevisitCandidate>& candidates,
                                        const std::vector<FeatureObservation>& features, const MapMemoryParams& params,
                                        const std::vector<FeatureObservation>& elsewhere) {
  constexpr int kNone = std::numeric_limits<int>::max();
  const double gate = chiSquaredQuantile(params.search_gate_probability, 2.0);
  const double max_var = params.max_search_sigma_px * params.max_search_sigma_px;
  // Best and second-best distances from each side, over the pairs inside the search region.
  struct Best {
    int index = -1;
    int distance = kNone;
    int second = kNone;
    void offer(int i, int d) {
      if (d < distance) {
        second = distance;
        distance = d;
        index = i;
      } else if (d < second) {
        second = d;
      }
    }
    bool passes(double ratio) const { return second == kNone || distance < ratio * second; }
  };
  std::vector<Best> of_landmark(candidates.size()), of_feature(features.size());
  for (size_t c = 0; c < candidates.size(); ++c) {
    const RevisitCandidate& lm = candidates[c];
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(lm.S);
    if (eig.info() != Eigen::Success || !(eig.eigenvalues().maxCoeff() <= max_var) ||
        !(eig.eigenvalues().minCoeff() > 0.0))
      continue;
    const Eigen::Matrix2d S_inv = lm.S.inverse();
    for (size_t f = 0; f < features.size(); ++f) {
      if (!features[f].descriptor || !features[f].uv.allFinite()) continue;
      const Eigen::Vector2d e = features[f].uv - lm.uv;
      if (!(e.dot(S_inv * e) <= gate)) continue;
      const int d = hammingDistance(lm.descriptor, *features[f].descriptor);
      of_landmark[c].offer(static_cast<int>(f), d);
      of_feature[f].offer(static_cast<int>(c), d);
    }
  }
  // The landmark's side of the ratio test is over the whole image: a look-alike anywhere in view
  // says the texture repeats, and the region's only look-alike may be another point while the
  // detector missed the landmark itself (a tiled floor: the one pattern everywhere).
  auto distinctInView = [&](size_t c, const Best& b) {
    auto alike = [&](const FeatureObservation& f) {
      return f.descriptor &&
             !(b.distance < params.descriptor_ratio * hammingDistance(candidates[c].descriptor, *f.descriptor));
    };
    for (size_t f = 0; f < features.size(); ++f)
      if (static_cast<int>(f) != b.index && alike(features[f])) return false;
    return std::none_of(elsewhere.begin(), elsewhere.end(), alike);
  };
  std::vector<RevisitMatch> matches;
  for (size_t c = 0; c < candidates.size(); ++c) {
    const Best& b = of_landmark[c];
    if (b.index < 0 || b.distance > params.max_descriptor_distance || !b.passes(params.descriptor_ratio)) continue;
    const Best& back = of_feature[static_cast<size_t>(b.index)];
    if (back.index != static_cast<int>(c) || !back.passes(params.descriptor_ratio)) continue;
    if (params.distinct_in_view && !distinctInView(c, b)) continue;
    matches.push_back({features[static_cast<size_t>(b.index)].id, candidates[c].landmark_id, b.distance});
  }
  return matches;
}

}  // namespace vi_ekf_slam
