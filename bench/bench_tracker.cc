// Front-end benchmarks: detection + KLT tracking per frame with 150 tracks, on rendered
// 699x540 hallway frames and on real 752x480 EuRoC frames (DATA_DIR; skipped without it).
// Frames are played forward and backward, so tracks continue as in a video.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "vi_ekf_slam/core/feature_tracker.h"
#include "vi_ekf_slam/io/datasets.h"
#include "vi_ekf_slam/sim/renderer.h"
#include "vi_ekf_slam/sim/scenarios.h"

using namespace vi_ekf_slam;

namespace {

struct Sequence {
  CameraModel camera;
  std::vector<cv::Mat> frames;
  std::vector<Eigen::Matrix3d> R_cur_prev;  ///< camera rotation from frame k-1 to k (forward play)
};

const Sequence& renderedSequence() {
  static const Sequence seq = [] {
    Sequence s;
    const sim::HallwayParams hp;
    const sim::Scenario sc = sim::hallwayScenario(hp, 1.0, 1);
    s.camera = sc.camera;
    const sim::Renderer renderer(sim::hallwayGeometry(hp), sc.camera, sc.T_b_c, sim::RenderParams());
    std::mt19937_64 rng(1);
    Quat q_prev;
    for (int k = 0; k < 40; ++k) {
      const double t = 8.0 + k / 28.0;
      s.frames.push_back(renderer.render(*sc.trajectory, t, rng));
      const Quat q_n_c = sc.trajectory->sample(t).q_n_b * Quat(sc.T_b_c.R_b_c);
      s.R_cur_prev.push_back(k == 0 ? Eigen::Matrix3d::Identity()
                                    : Eigen::Matrix3d((q_n_c.conjugate() * q_prev).toRotationMatrix()));
      q_prev = q_n_c;
    }
    return s;
  }();
  return seq;
}

const Sequence* eurocSequence() {
  static const std::unique_ptr<Sequence> seq = []() -> std::unique_ptr<Sequence> {
    const char* dir = std::getenv("DATA_DIR");
    if (!dir) return nullptr;
    const std::string cam = std::string(dir) + "/euroc_v1_01_micro/mav0/cam0";
    if (!std::ifstream(cam + "/sensor.yaml")) return nullptr;
    auto s = std::make_unique<Sequence>();
    s->camera = CameraModel(io::readAslCamera(cam + "/sensor.yaml").intrinsics);
    for (const auto& im : io::readAslImages(cam)) {
      s->frames.push_back(cv::imread(im.path, cv::IMREAD_GRAYSCALE));
      s->R_cur_prev.push_back(Eigen::Matrix3d::Identity());  // the MAV stands still
    }
    return s;
  }();
  return seq.get();
}

void runTracker(::benchmark::State& st, const Sequence& seq) {
  TrackerParams p;
  p.max_tracks = 150;
  FeatureTracker tracker(seq.camera, p);
  const int n = static_cast<int>(seq.frames.size());
  int k = 0, dir = 1;
  double t = 0.0;
  long tracks = 0, frames = 0;
  for (auto _ : st) {
    // Forward: R_cur_prev of frame k; backward: its inverse from frame k+1.
    const Eigen::Matrix3d R = dir > 0 ? seq.R_cur_prev[static_cast<size_t>(k)]
                                      : Eigen::Matrix3d(seq.R_cur_prev[static_cast<size_t>(k + 1)].transpose());
    const CameraFrame f = tracker.track(t, seq.frames[static_cast<size_t>(k)], R);
    benchmark::DoNotOptimize(f.features.data());
    tracks += static_cast<long>(f.features.size());
    ++frames;
    t += 0.05;
    if (k + dir < 0 || k + dir >= n) dir = -dir;
    k += dir;
  }
  st.counters["tracks_per_frame"] = frames ? static_cast<double>(tracks) / frames : 0.0;
}

void BM_TrackerRendered699x540(::benchmark::State& st) { runTracker(st, renderedSequence()); }
BENCHMARK(BM_TrackerRendered699x540)->Unit(::benchmark::kMillisecond)->MinTime(2.0);

void BM_TrackerEuroc752x480(::benchmark::State& st) {
  const Sequence* seq = eurocSequence();
  if (!seq) {
    st.SkipWithError("EuRoC frames not found (DATA_DIR)");
    for (auto _ : st) {
    }
    return;
  }
  runTracker(st, *seq);
}
BENCHMARK(BM_TrackerEuroc752x480)->Unit(::benchmark::kMillisecond)->MinTime(2.0);

}  // namespace
