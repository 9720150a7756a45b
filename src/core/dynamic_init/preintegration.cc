#include "vi_ekf_slam/core/dynamic_init/preintegration.h"

#include <algorithm>

#include "vi_ekf_slam/core/so3.h"

namespace vi_ekf_slam {
namespace alignment {

ImuData interpolate(const std::deque<ImuData>& imu, double t) {
  if (t <= imu.front().timestamp) return imu.front();
  if (t >= imu.back().timestamp) return imu.back();
  auto it = std::lower_bound(imu.begin(), imu.end(), t, [](const ImuData& d, double x) { return d.timestamp < x; });
  const ImuData& b = *it;
  const ImuData& a = *(it - 1);
  const double s = (t - a.timestamp) / (b.timestamp - a.timestamp);
  return {t, a.wm + s * (b.wm - a.wm), a.am + s * (b.am - a.am)};
}

std::vector<Preintegrated> preintegrate(const std::deque<ImuData>& imu, const std::vector<double>& times,
                                        const Vec3& b_g) {
  std::vector<double> cuts;
  for (const auto& d : imu) {
    if (d.timestamp > times.front() && d.timestamp < times.back()) cuts.push_back(d.timestamp);
  }
  cuts.insert(cuts.end(), times.begin(), times.end());
  std::sort(cuts.begin(), cuts.end());
  std::vector<Preintegrated> out;
  Preintegrated cur;
  size_t next = 0;
  out.push_back(cur);
  ++next;
  for (size_t i = 1; i < cuts.size() && next < times.size(); ++i) {
    const double a = cuts[i - 1], b = cuts[i], dt = b - a;
    if (dt > 0.0) {
      const ImuData m = interpolate(imu, 0.5 * (a + b));  // midpoint rule
      const Vec3 w = m.wm - b_g;
      const Mat3 R_mid = cur.R * expSO3(0.5 * dt * w);
      const Vec3 acc = R_mid * m.am;
      cur.alpha += cur.beta * dt + 0.5 * acc * dt * dt;
      cur.beta += acc * dt;
      cur.A += cur.B * dt - 0.5 * R_mid * dt * dt;
      cur.B -= R_mid * dt;
      cur.R = cur.R * expSO3(dt * w);
    }
    while (next < times.size() && times[next] <= b) {
      out.push_back(cur);
      ++next;
    }
  }
  while (out.size() < times.size()) out.push_back(cur);
  return out;
}

}  // namespace alignment
}  // namespace vi_ekf_slam
