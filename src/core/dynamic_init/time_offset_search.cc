#include "vi_ekf_slam/core/dynamic_init/time_offset_search.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vi_ekf_slam {
namespace alignment {

TimeOffsetFit searchTimeOffset(AlignmentProblem& problem, double search_s) {
  TimeOffsetFit fit;
  if (search_s <= 0.0) {
    problem.refine(0.0, true);
    return fit;
  }
  constexpr double kStep = 0.01;
  const int n = static_cast<int>(std::floor(search_s / kStep));
  double best_score = std::numeric_limits<double>::infinity();
  for (int i = -n; i <= n; ++i) {
    const double c = problem.refine(i * kStep, true);
    const double score = c / std::max(1, problem.activeObservations());
    if (score < best_score) {
      best_score = score;
      fit.dt_s = i * kStep;
    }
  }
  problem.refine(fit.dt_s, true);
  const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
  double lo = std::max(-search_s, fit.dt_s - kStep), hi = std::min(search_s, fit.dt_s + kStep);
  double x1 = hi - phi * (hi - lo), x2 = lo + phi * (hi - lo);
  double f1 = problem.refine(x1), f2 = problem.refine(x2);
  for (int it = 0; it < 12; ++it) {  // the bracket shrinks to 0.3% of 20 ms
    if (f1 < f2) {
      hi = x2;
      x2 = x1;
      f2 = f1;
      x1 = hi - phi * (hi - lo);
      f1 = problem.refine(x1);
    } else {
      lo = x1;
      x1 = x2;
      f1 = f2;
      x2 = lo + phi * (hi - lo);
      f2 = problem.refine(x2);
    }
  }
  fit.dt_s = f1 < f2 ? x1 : x2;
  const double fb = std::min(f1, f2), fa = problem.refine(fit.dt_s - kStep), fc = problem.refine(fit.dt_s + kStep);
  const double den = fa - 2.0 * fb + fc;
  if (std::isfinite(den) && den > 0.0) fit.curvature = den / (kStep * kStep);
  return fit;
}

}  // namespace alignment
}  // namespace vi_ekf_slam
