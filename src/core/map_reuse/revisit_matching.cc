#include "vi_ekf_slam/core/map_reuse/revisit_matching.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <bitset>
#include <opencv2/core.hpp>

#include "vi_ekf_slam/core/chi_squared.h"
#include "vi_ekf_slam/core/map_reuse/descriptor_matching.h"

namespace vi_ekf_slam {

int hammingDistance(const Descriptor& a, const Descriptor& b) {
  int d = 0;
  for (size_t i = 0; i < a.size(); ++i) d += static_cast<int>(std::bitset<8>(a[i] ^ b[i]).count());
  return d;
}

bool pendingRevisitAgrees(const Eigen::Vector2d& e, const Eigen::Matrix2d& S, const Eigen::Vector2d& first_e,
                          double gate_probability, double pixel_noise_px, const MapReuseParams& params) {
  const Eigen::LLT<Eigen::Matrix2d> llt(S);  // (fails on a covariance that is not positive definite)
  if (llt.info() != Eigen::Success || !e.allFinite() || !first_e.allFinite()) return false;
  const double nis = e.dot(llt.solve(e));
  const double drift = (e - first_e).squaredNorm() / (2.0 * pixel_noise_px * pixel_noise_px);
  return nis <= chiSquaredQuantile(gate_probability, 2.0) &&
         drift <= chiSquaredQuantile(params.search_gate_probability, 2.0);
}

std::vector<RevisitMatch> matchRevisits(const std::vector<RevisitCandidate>& candidates,
                                        const std::vector<FeatureObservation>& features, const MapReuseParams& params,
                                        const std::vector<FeatureObservation>& elsewhere) {
  if (candidates.empty() || features.empty()) return {};
  const double gate = chiSquaredQuantile(params.search_gate_probability, 2.0);
  const double max_var = params.max_search_sigma_px * params.max_search_sigma_px;
  // The pairs inside the search region, of a feature with an appearance.
  cv::Mat inside = cv::Mat::zeros(static_cast<int>(candidates.size()), static_cast<int>(features.size()), CV_8U);
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
      if (e.dot(S_inv * e) <= gate) inside.at<std::uint8_t>(static_cast<int>(c), static_cast<int>(f)) = 1;
    }
  }
  std::vector<Descriptor> lm_d, f_d;
  for (const auto& c : candidates) lm_d.push_back(c.descriptor);
  for (const auto& f : features) f_d.push_back(f.descriptor.value_or(Descriptor{}));
  const cv::Mat L = descriptorRows(lm_d), F = descriptorRows(f_d);
  // Best and second-best distances from each side, over the pairs inside the search region.
  const std::vector<NearestTwo> of_landmark = nearestTwo(L, F, inside), of_feature = nearestTwo(F, L, inside.t());
  // The landmark's side of the ratio test is over the whole image: a look-alike anywhere in view
  // says the texture repeats, and the region's only look-alike may be another point while the
  // detector missed the landmark itself (a tiled floor: the one pattern everywhere). Its nearest
  // other feature with an appearance, here or elsewhere, must be clearly farther than its match.
  std::vector<Descriptor> other_d;
  std::vector<int> feature_of;  // index into features, -1: elsewhere
  for (size_t f = 0; f < features.size(); ++f) {
    if (!features[f].descriptor) continue;
    other_d.push_back(*features[f].descriptor);
    feature_of.push_back(static_cast<int>(f));
  }
  for (const auto& e : elsewhere) {
    if (!e.descriptor) continue;
    other_d.push_back(*e.descriptor);
    feature_of.push_back(-1);
  }
  const cv::Mat O = descriptorRows(other_d);
  auto distinctInView = [&](size_t c, const NearestTwo& b) {
    const NearestTwo all = nearestTwo(L.row(static_cast<int>(c)), O).front();
    // The nearest other than the match itself.
    const int other =
        all.index >= 0 && feature_of[static_cast<size_t>(all.index)] == b.index ? all.second : all.distance;
    return other == NearestTwo::kNone || b.distance < params.descriptor_ratio * other;
  };
  std::vector<RevisitMatch> matches;
  for (size_t c = 0; c < candidates.size(); ++c) {
    const NearestTwo& b = of_landmark[c];
    if (b.index < 0 || b.distance > params.max_descriptor_distance || !b.passesRatio(params.descriptor_ratio)) continue;
    const NearestTwo& back = of_feature[static_cast<size_t>(b.index)];
    if (back.index != static_cast<int>(c) || !back.passesRatio(params.descriptor_ratio)) continue;
    if (params.distinct_in_view && !distinctInView(c, b)) continue;
    matches.push_back({features[static_cast<size_t>(b.index)].id, candidates[c].landmark_id, b.distance});
  }
  return matches;
}

}  // namespace vi_ekf_slam
