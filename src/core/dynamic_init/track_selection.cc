#include "vi_ekf_slam/core/dynamic_init/track_selection.h"

#include <algorithm>
#include <map>

namespace vi_ekf_slam {
namespace alignment {

std::vector<Track> selectTracks(const std::vector<const CameraFrame*>& window, const CameraModel& camera,
                                int min_observations, size_t max_tracks) {
  std::map<std::int64_t, std::vector<Observation>> by_id;
  for (int k = 0; k < static_cast<int>(window.size()); ++k) {
    for (const auto& f : window[static_cast<size_t>(k)]->features) {
      Eigen::Vector2d xn;
      if (f.uv.allFinite() && camera.pixelToNormalized(f.uv, &xn)) by_id[f.id].push_back({k, xn, f.uv});
    }
  }
  std::vector<Track> tracks;
  for (auto& [id, obs] : by_id) {
    if (static_cast<int>(obs.size()) >= min_observations) tracks.push_back({id, std::move(obs)});
  }
  std::stable_sort(tracks.begin(), tracks.end(), [](const Track& a, const Track& b) {
    return a.observations.size() != b.observations.size() ? a.observations.size() > b.observations.size() : a.id < b.id;
  });
  if (tracks.size() > max_tracks) tracks.resize(max_tracks);
  return tracks;
}

}  // namespace alignment
}  // namespace vi_ekf_slam
