#include "vi_ekf_slam/sim/renderer.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

namespace vi_ekf_slam::sim {

namespace {

double uniform(std::mt19937_64& rng, double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }

/// A poster: a framed rectangle with stripes, checks or discs inside.
void drawPoster(cv::Mat& tex, const cv::Rect& r, std::mt19937_64& rng) {
  const int bg = static_cast<int>(uniform(rng, 170, 240));
  cv::rectangle(tex, r, cv::Scalar(bg), cv::FILLED);
  cv::rectangle(tex, r, cv::Scalar(30), std::max(2, r.width / 40));
  const int kind = static_cast<int>(uniform(rng, 0, 3));
  const int n = static_cast<int>(uniform(rng, 3, 8));
  for (int i = 0; i < n; ++i) {
    const int g = static_cast<int>(uniform(rng, 10, 120));
    const int x = r.x + static_cast<int>(uniform(rng, 0.1, 0.7) * r.width);
    const int y = r.y + static_cast<int>(uniform(rng, 0.1, 0.7) * r.height);
    const int w = static_cast<int>(uniform(rng, 0.08, 0.3) * r.width);
    const int h = static_cast<int>(uniform(rng, 0.08, 0.3) * r.height);
    if (kind == 0) cv::rectangle(tex, cv::Rect(x, y, w, h), cv::Scalar(g), cv::FILLED);
    if (kind == 1) cv::circle(tex, cv::Point(x, y), std::max(3, w / 2), cv::Scalar(g), cv::FILLED);
    if (kind == 2) {
      for (int k = 0; k < 4; ++k) {
        cv::rectangle(tex, cv::Rect(x + k * w / 4, y, w / 8 + 1, h), cv::Scalar((k % 2) ? g : 255 - g), cv::FILLED);
      }
    }
  }
}

}  // namespace

cv::Mat makeTexture(const Quad& q, double texel, std::mt19937_64& rng) {
  const int W = std::max(8, static_cast<int>(std::ceil(q.u_len / texel)));
  const int H = std::max(8, static_cast<int>(std::ceil(q.v_len / texel)));
  auto px = [&](double metres) { return static_cast<int>(std::lround(metres / texel)); };
  // Base: mid-grey with a smooth low-frequency variation.
  cv::Mat low(std::max(2, H / 50), std::max(2, W / 50), CV_32F);
  cv::RNG cvrng(static_cast<uint64>(rng()));
  cvrng.fill(low, cv::RNG::UNIFORM, 115, 150);
  cv::Mat base;
  cv::resize(low, base, cv::Size(W, H), 0, 0, cv::INTER_CUBIC);
  cv::Mat tex;
  base.convertTo(tex, CV_8U);
  if (q.kind == "floor") {
    // 0.5 m tiles of slightly different brightness with dark grout lines.
    for (int a = 0; a < W; a += px(0.5)) {
      for (int b = 0; b < H; b += px(0.5)) {
        const int g = static_cast<int>(uniform(rng, 90, 140));
        cv::rectangle(tex, cv::Rect(a, b, px(0.5), px(0.5)), cv::Scalar(g), cv::FILLED);
      }
    }
    for (int a = 0; a < W; a += px(0.5)) cv::line(tex, {a, 0}, {a, H}, cv::Scalar(45), 2);
    for (int b = 0; b < H; b += px(0.5)) cv::line(tex, {0, b}, {W, b}, cv::Scalar(45), 2);
  } else if (q.kind == "ceiling") {
    for (int a = 0; a < W; a += px(0.6)) cv::line(tex, {a, 0}, {a, H}, cv::Scalar(70), 2);
    for (int b = 0; b < H; b += px(0.6)) cv::line(tex, {0, b}, {W, b}, cv::Scalar(70), 2);
    for (int a = px(1.0); a + px(1.2) < W; a += px(3.0)) {
      const int b = std::max(0, H / 2 - px(0.15));
      cv::rectangle(tex, cv::Rect(a, b, px(1.2), px(0.3)), cv::Scalar(245), cv::FILLED);
      cv::rectangle(tex, cv::Rect(a, b, px(1.2), px(0.3)), cv::Scalar(60), 2);
    }
  } else {
    // Walls. Height above the floor of texel row b: v points up (-z) or down (+z).
    const bool v_up = q.v.z() < 0.0;
    auto row = [&](double height) { return v_up ? px(height) : H - px(height); };
    auto band = [&](double h0, double h1) {
      const int r0 = row(h0), r1 = row(h1);
      return std::make_pair(std::min(r0, r1), std::max(r0, r1));
    };
    // Repeating wall panels every 1.2 m (thin vertical joints), and a baseboard.
    for (int a = px(0.6); a < W; a += px(1.2)) cv::line(tex, {a, 0}, {a, H}, cv::Scalar(85), 2);
    const auto [bb0, bb1] = band(0.0, 0.12);
    cv::rectangle(tex, cv::Rect(0, bb0, W, std::max(1, bb1 - bb0)), cv::Scalar(40), cv::FILLED);
    // Door frames roughly every 5-8 m, posters in between.
    double a_m = uniform(rng, 1.0, 3.0);
    while (a_m + 1.2 < q.u_len) {
      if (uniform(rng, 0, 1) < 0.45) {
        const auto [d0, d1] = band(0.0, 2.1);
        const cv::Rect door(px(a_m), d0, px(0.95), d1 - d0);
        cv::rectangle(tex, door, cv::Scalar(static_cast<int>(uniform(rng, 50, 90))), cv::FILLED);
        cv::rectangle(tex, door, cv::Scalar(200), std::max(2, px(0.06)));
        cv::circle(tex, {door.x + px(0.8), (d0 + d1) / 2}, std::max(2, px(0.03)), cv::Scalar(230), cv::FILLED);
        a_m += uniform(rng, 2.5, 4.5);
      } else {
        const double w = uniform(rng, 0.4, 1.0), h = uniform(rng, 0.4, 0.9), h0 = uniform(rng, 0.9, 1.5);
        const auto [p0, p1] = band(h0, h0 + h);
        drawPoster(tex, cv::Rect(px(a_m), p0, px(w), p1 - p0), rng);
        a_m += w + uniform(rng, 0.8, 2.5);
      }
    }
  }
  // Speckle: small dark and bright dots (texture for close range, some corners everywhere).
  const int dots = static_cast<int>(q.area() * 25.0);
  for (int i = 0; i < dots; ++i) {
    const cv::Point c(static_cast<int>(uniform(rng, 0, W)), static_cast<int>(uniform(rng, 0, H)));
    const int r = std::max(1, px(uniform(rng, 0.01, 0.035)));
    cv::circle(tex, c, r, cv::Scalar(uniform(rng, 0, 1) < 0.5 ? uniform(rng, 20, 70) : uniform(rng, 190, 250)),
               cv::FILLED);
  }
  return tex;
}

Renderer::Renderer(const std::vector<Quad>& quads, const CameraModel& camera, const CameraExtrinsics& T_b_c,
                   const RenderParams& params)
    : camera_(camera), T_b_c_(T_b_c), params_(params) {
  std::mt19937_64 rng(params.texture_seed);
  for (const auto& q : quads) {
    Surface s;
    s.quad = q;
    cv::Mat t;
    makeTexture(q, params.texel_m, rng).convertTo(t, CV_32F);
    s.mips.push_back(t);
    while (s.mips.size() < 7 && s.mips.back().cols > 16 && s.mips.back().rows > 16) {
      cv::Mat d;
      cv::pyrDown(s.mips.back(), d);
      s.mips.push_back(d);
    }
    surfaces_.push_back(std::move(s));
  }
  rays_.create(camera.height(), camera.width(), CV_32FC3);
  for (int v = 0; v < camera.height(); ++v) {
    for (int u = 0; u < camera.width(); ++u) {
      Eigen::Vector2d xn;
      if (!camera.pixelToNormalized(Eigen::Vector2d(u, v), &xn)) xn.setZero();
      const Eigen::Vector3d r = Eigen::Vector3d(xn.x(), xn.y(), 1.0).normalized();
      rays_.at<cv::Vec3f>(v, u) =
          cv::Vec3f(static_cast<float>(r.x()), static_cast<float>(r.y()), static_cast<float>(r.z()));
    }
  }
}

cv::Mat Renderer::renderPose(const Vec3& p_n_b, const Quat& q_n_b) const {
  const Eigen::Matrix3f R = (q_n_b.toRotationMatrix() * T_b_c_.R_b_c).cast<float>();
  const Eigen::Vector3f o = (p_n_b + q_n_b * T_b_c_.p_b_c).cast<float>();
  cv::Mat out(rays_.size(), CV_32F, cv::Scalar(128));
  const float pixel_angle = static_cast<float>(1.0 / camera_.intrinsics().fx);
  const float texel = static_cast<float>(params_.texel_m);
  struct Plane {
    Eigen::Vector3f o, u, v, n;
    float ul, vl;
  };
  std::vector<Plane> planes;
  for (const auto& s : surfaces_) {
    planes.push_back({s.quad.origin.cast<float>(), s.quad.u.cast<float>(), s.quad.v.cast<float>(),
                      s.quad.normal().cast<float>(), static_cast<float>(s.quad.u_len),
                      static_cast<float>(s.quad.v_len)});
  }
  cv::parallel_for_(cv::Range(0, rays_.rows), [&](const cv::Range& range) {
    for (int y = range.start; y < range.end; ++y) {
      const cv::Vec3f* ray = rays_.ptr<cv::Vec3f>(y);
      float* dst = out.ptr<float>(y);
      for (int x = 0; x < rays_.cols; ++x) {
        const Eigen::Vector3f d = R * Eigen::Vector3f(ray[x][0], ray[x][1], ray[x][2]);
        float best_t = 1e9f, best_a = 0, best_b = 0, best_cos = 1;
        int best = -1;
        for (size_t k = 0; k < planes.size(); ++k) {
          const Plane& p = planes[k];
          const float denom = p.n.dot(d);
          if (denom > -1e-4f) continue;  // seen from behind or edge-on
          const float t = p.n.dot(p.o - o) / denom;
          if (t <= 0.02f || t >= best_t) continue;
          const Eigen::Vector3f h = o + t * d - p.o;
          const float a = h.dot(p.u), b = h.dot(p.v);
          if (a < 0 || b < 0 || a > p.ul || b > p.vl) continue;
          best = static_cast<int>(k);
          best_t = t;
          best_a = a;
          best_b = b;
          best_cos = -denom;
        }
        if (best < 0) continue;
        // Mip level from the pixel footprint on the surface in texels.
        const auto& mips = surfaces_[static_cast<size_t>(best)].mips;
        const float footprint = best_t * pixel_angle / (texel * std::max(0.05f, best_cos));
        int level = footprint > 1.0f ? static_cast<int>(std::log2(footprint)) : 0;
        level = std::min(level, static_cast<int>(mips.size()) - 1);
        const cv::Mat& m = mips[static_cast<size_t>(level)];
        const float scale = 1.0f / (texel * static_cast<float>(1 << level));
        const float fx = std::clamp(best_a * scale - 0.5f, 0.0f, m.cols - 1.001f);
        const float fy = std::clamp(best_b * scale - 0.5f, 0.0f, m.rows - 1.001f);
        const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
        const float ax = fx - ix, ay = fy - iy;
        const float* r0 = m.ptr<float>(iy);
        const float* r1 = m.ptr<float>(std::min(iy + 1, m.rows - 1));
        const int ix1 = std::min(ix + 1, m.cols - 1);
        dst[x] = (1 - ay) * ((1 - ax) * r0[ix] + ax * r0[ix1]) + ay * ((1 - ax) * r1[ix] + ax * r1[ix1]);
      }
    }
  });
  return out;
}

cv::Mat Renderer::render(const Trajectory& traj, double t, std::mt19937_64& rng) const {
  cv::Mat acc;
  const int n = std::max(1, params_.motion_blur_samples);
  for (int i = 0; i < n; ++i) {
    const double ti = n == 1 ? t : t + params_.exposure_s * (static_cast<double>(i) / (n - 1) - 0.5);
    const TrajectorySample s = traj.sample(ti);
    const cv::Mat img = renderPose(s.p_n_b, s.q_n_b);
    if (acc.empty())
      acc = img / n;
    else
      acc += img / n;
  }
  if (params_.noise_sigma > 0.0) {
    cv::Mat noise(acc.size(), CV_32F);
    cv::RNG cvrng(static_cast<uint64>(rng()));
    cvrng.fill(noise, cv::RNG::NORMAL, 0.0, params_.noise_sigma);
    acc += noise;
  }
  cv::Mat out;
  acc.convertTo(out, CV_8U);
  return out;
}

}  // namespace vi_ekf_slam::sim
