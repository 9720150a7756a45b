#include "vi_ekf_slam/eval/run_health.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace vi_ekf_slam::eval {

nlohmann::ordered_json runHealth(const std::vector<StatusSample>& tr, int resets, double input_s, double wall_s) {
  nlohmann::ordered_json h;
  double path = 0.0, tracks = 0.0, accepted = 0.0, rejected = 0.0, nis = 0.0, ms = 0.0, tracker_ms = 0.0;
  int revisits = 0;
  int nis_n = 0, min_tracks = tr.empty() ? 0 : 1 << 30;
  std::vector<double> speeds;
  for (size_t i = 0; i < tr.size(); ++i) {
    const StatusSample& s = tr[i];
    tracks += s.tracks;
    min_tracks = std::min(min_tracks, s.tracks);
    accepted += s.accepted;
    rejected += s.rejected;
    ms += s.processing_ms;
    revisits += s.revisits;
    tracker_ms += s.tracker_ms;
    if (s.accepted > 0) {
      nis += s.nis_per_dof;
      ++nis_n;
    }
    if (i > 0 && tr[i - 1].resets == s.resets && s.t > tr[i - 1].t) {
      const double d = (s.p - tr[i - 1].p).norm();
      path += d;
      speeds.push_back(d / (s.t - tr[i - 1].t));
    }
  }
  const double n = std::max<double>(1.0, static_cast<double>(tr.size()));
  std::sort(speeds.begin(), speeds.end());
  h["images"] = tr.size();
  h["resets"] = resets;
  h["path_length_m"] = path;
  h["speed_p99_mps"] = speeds.empty() ? 0.0 : speeds[static_cast<size_t>(0.99 * (speeds.size() - 1))];
  h["tracks_mean"] = tracks / n;
  h["tracks_min"] = min_tracks;
  h["accepted_per_image"] = accepted / n;
  h["rejected_per_image"] = rejected / n;
  h["rejected_fraction"] = accepted + rejected > 0 ? rejected / (accepted + rejected) : 0.0;
  h["nis_per_dof_mean"] = nis_n ? nis / nis_n : 0.0;
  h["time_offset_s"] = tr.empty() ? 0.0 : tr.back().time_offset_s;
  h["time_offset_sigma_s"] = tr.empty() ? 0.0 : tr.back().time_offset_sigma_s;
  h["processing_ms_mean"] = ms / n;
  h["tracker_ms_mean"] = tracker_ms / n;
  h["reading_ms_mean"] = tr.empty() ? 0.0 : std::max(0.0, 1000.0 * wall_s / n - ms / n);
  h["real_time_factor"] = wall_s > 0.0 ? input_s / wall_s : 0.0;  // offline: input reading included
  h["revisits"] = revisits;
  h["dormant_landmarks_final"] = tr.empty() ? 0 : tr.back().dormant;
  return h;
}

std::string healthLine(const std::string& name, const nlohmann::ordered_json& h) {
  char buf[1024];
  std::snprintf(
      buf, sizeof(buf),
      "%s: %d images, %d resets, path %.2f m (speed p99 %.2f m/s), tracks per image %.1f (min %d), observations "
      "per image %.1f accepted / %.1f rejected, NIS per dof %.2f, time offset %.4f +- %.4f s\n"
      "  per image: %.2f ms processing, of which %.2f ms tracking; bag reading and the rest %.2f ms (%.1fx real "
      "time)\n",
      name.c_str(), h["images"].get<int>(), h["resets"].get<int>(), h["path_length_m"].get<double>(),
      h["speed_p99_mps"].get<double>(), h["tracks_mean"].get<double>(), h["tracks_min"].get<int>(),
      h["accepted_per_image"].get<double>(), h["rejected_per_image"].get<double>(), h["nis_per_dof_mean"].get<double>(),
      h["time_offset_s"].get<double>(), h["time_offset_sigma_s"].get<double>(), h["processing_ms_mean"].get<double>(),
      h["tracker_ms_mean"].get<double>(), h["reading_ms_mean"].get<double>(), h["real_time_factor"].get<double>());
  std::string out = buf;
  if (h.contains("revisits") && h["revisits"].get<int>() > 0) {
    std::snprintf(buf, sizeof(buf), "  map kept: dormant landmarks found again %d times, %d dormant at the end\n",
                  h["revisits"].get<int>(), h["dormant_landmarks_final"].get<int>());
    out += buf;
  }
  return out;
}

std::vector<ReportColumn> healthColumns() {
  return {{"images", "images", 0},
          {"resets", "resets", 0},
          {"path_length_m", "path [m]", 2},
          {"speed_p99_mps", "speed p99 [m/s]", 2},
          {"tracks_mean", "tracks", 1},
          {"accepted_per_image", "accepted", 1},
          {"rejected_per_image", "rejected", 1},
          {"nis_per_dof_mean", "NIS/dof", 2},
          {"time_offset_s", "time offset [s]", 4},
          {"processing_ms_mean", "ms/image", 1},
          {"real_time_factor", "real-time factor", 1},
          {"/references/0/position_rmse_m", "ref. RMSE [m]", 3},
          {"/references/0/scale_reference_units_per_m", "ref. scale", 3},
          {"/references/0/rotation_rmse_deg", "ref. rot [deg]", 2}};
}

void writeTrace(const std::string& path, const std::vector<StatusSample>& samples) {
  std::ofstream f(path);
  f << "t,x,y,z,tracks,accepted,rejected,nis_per_dof,time_offset_s,time_offset_sigma_s,resets,processing_ms,"
       "tracker_ms,landmarks,new_landmarks,deferred,removed,stationary,dormant,revisits,speed_mps,velocity_sigma_mps,"
       "blind_s\n"
    << std::setprecision(12);
  for (const StatusSample& s : samples) {
    f << s.t << "," << s.p.x() << "," << s.p.y() << "," << s.p.z() << "," << s.tracks << "," << s.accepted << ","
      << s.rejected << "," << s.nis_per_dof << "," << s.time_offset_s << "," << s.time_offset_sigma_s << "," << s.resets
      << "," << s.processing_ms << "," << s.tracker_ms << "," << s.landmarks << "," << s.new_landmarks << ","
      << s.deferred << "," << s.removed << "," << static_cast<int>(s.stationary) << "," << s.dormant << ","
      << s.revisits << "," << s.speed_mps << "," << s.velocity_sigma_mps << "," << s.blind_s << "\n";
  }
}

}  // namespace vi_ekf_slam::eval
