#include "vi_ekf_slam/core/camera_model.h"

#include <Eigen/LU>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace vi_ekf_slam {

CameraIntrinsics pinholeIntrinsics(int width, int height, double f_px) {
  CameraIntrinsics in;
  in.width = width;
  in.height = height;
  in.fx = in.fy = f_px;
  in.cx = 0.5 * width;
  in.cy = 0.5 * height;
  return in;
}

std::string CameraIntrinsics::validate() const {
  std::ostringstream err;
  const double v[] = {fx, fy, cx, cy};
  for (double x : v) {
    if (!std::isfinite(x)) err << "non-finite intrinsic; ";
  }
  if (!(fx > 0.0) || !(fy > 0.0)) err << "focal lengths must be > 0 (fx=" << fx << ", fy=" << fy << "); ";
  if (width <= 0 || height <= 0) err << "image size must be > 0 (" << width << "x" << height << "); ";
  for (double d : distortion) {
    if (!std::isfinite(d)) err << "non-finite distortion coefficient; ";
  }
  if (model == DistortionModel::kRadTan &&
      !(distortion.size() == 4 || distortion.size() == 5 || distortion.size() == 8 || distortion.empty())) {
    err << "plumb_bob needs 4 or 5 coefficients (k1 k2 p1 p2 [k3]); ";
  }
  if (model == DistortionModel::kEquidistant && distortion.size() != 4) {
    err << "equidistant needs 4 coefficients (k1 k2 k3 k4); ";
  }
  return err.str();
}

CameraModel::CameraModel(const CameraIntrinsics& intrinsics) : intr_(intrinsics) {
  const std::string err = intr_.validate();
  if (!err.empty()) throw std::invalid_argument("CameraModel: " + err);
  for (size_t i = 0; i < intr_.distortion.size() && i < 5; ++i) k_[i] = intr_.distortion[i];
  if (intr_.distortion.size() == 8 && intr_.model == DistortionModel::kRadTan) {
    // The 8-coefficient rational model is only accepted when the rational part is zero.
    for (size_t i = 5; i < 8; ++i) {
      if (intr_.distortion[i] != 0.0) throw std::invalid_argument("CameraModel: rational model unsupported");
    }
  }
}

Eigen::Vector2d CameraModel::distort(const Eigen::Vector2d& xn, Eigen::Matrix2d* J) const {
  const double x = xn.x(), y = xn.y();
  switch (intr_.model) {
    case DistortionModel::kNone:
      if (J) J->setIdentity();
      return xn;
    case DistortionModel::kRadTan: {
      const double k1 = k_[0], k2 = k_[1], p1 = k_[2], p2 = k_[3], k3 = k_[4];
      const double r2 = x * x + y * y;
      const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
      const double dradial = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);  // d(radial)/d(r2)
      Eigen::Vector2d xd(x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
                         y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y);
      if (J) {
        const double cross = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
        *J << radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x, cross, cross,
            radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x;
      }
      return xd;
    }
    case DistortionModel::kEquidistant: {
      const double r = xn.norm();
      if (r < 1e-9) {
        if (J) J->setIdentity();
        return xn;
      }
      const double th = std::atan(r), t2 = th * th;
      const double thd = th * (1.0 + t2 * (k_[0] + t2 * (k_[1] + t2 * (k_[2] + t2 * k_[3]))));
      const double s = thd / r;
      if (J) {
        const double dthd_dth = 1.0 + t2 * (3.0 * k_[0] + t2 * (5.0 * k_[1] + t2 * (7.0 * k_[2] + t2 * 9.0 * k_[3])));
        const double ds_dr = (dthd_dth / (1.0 + r * r) * r - thd) / (r * r);
        *J = s * Eigen::Matrix2d::Identity() + ds_dr * xn * xn.transpose() / r;
      }
      return s * xn;
    }
  }
  return xn;
}

Eigen::Vector2d CameraModel::normalizedToPixel(const Eigen::Vector2d& xn, Eigen::Matrix2d* J) const {
  Eigen::Matrix2d Jd;
  const Eigen::Vector2d xd = distort(xn, J ? &Jd : nullptr);
  if (J) {
    J->row(0) = intr_.fx * Jd.row(0);
    J->row(1) = intr_.fy * Jd.row(1);
  }
  return {intr_.fx * xd.x() + intr_.cx, intr_.fy * xd.y() + intr_.cy};
}

bool CameraModel::pixelToNormalized(const Eigen::Vector2d& uv, Eigen::Vector2d* xn, Eigen::Matrix2d* J) const {
  const Eigen::Vector2d xd((uv.x() - intr_.cx) / intr_.fx, (uv.y() - intr_.cy) / intr_.fy);
  // Gauss-Newton on distort(x) = xd with the analytic Jacobian, so the inverse is exactly
  // consistent with the forward model (OpenCV's fixed-point undistortion stops after a few
  // iterations and leaves sub-pixel errors under strong distortion such as EuRoC's k1=-0.28).
  Eigen::Vector2d x = xd;
  Eigen::Matrix2d Jd;
  bool converged = false;
  for (int it = 0; it < 30; ++it) {
    const Eigen::Vector2d r = distort(x, &Jd) - xd;
    if (!r.allFinite()) return false;
    const Eigen::Vector2d step = Jd.partialPivLu().solve(r);
    x -= step;
    if (step.squaredNorm() < 1e-26) {
      converged = true;
      break;
    }
  }
  if (!converged || !x.allFinite()) return false;
  distort(x, &Jd);
  if (std::abs(Jd.determinant()) < 1e-9) return false;
  *xn = x;
  if (J) {
    Eigen::Matrix2d Jpix;  // d(uv)/d(xn)
    Jpix.row(0) = intr_.fx * Jd.row(0);
    Jpix.row(1) = intr_.fy * Jd.row(1);
    *J = Jpix.inverse();
  }
  return true;
}

bool CameraModel::project(const Eigen::Vector3d& p_c, Eigen::Vector2d* uv, Eigen::Matrix<double, 2, 3>* J) const {
  if (!(p_c.z() > 1e-6)) return false;
  const double iz = 1.0 / p_c.z();
  const Eigen::Vector2d xn(p_c.x() * iz, p_c.y() * iz);
  Eigen::Matrix2d Jn;
  *uv = normalizedToPixel(xn, J ? &Jn : nullptr);
  if (J) {
    Eigen::Matrix<double, 2, 3> Jproj;  // d(xn)/d(p_c)
    Jproj << iz, 0.0, -xn.x() * iz, 0.0, iz, -xn.y() * iz;
    *J = Jn * Jproj;
  }
  return uv->allFinite();
}

bool CameraModel::inImage(const Eigen::Vector2d& uv, double border_px) const {
  return uv.x() >= border_px && uv.y() >= border_px && uv.x() <= intr_.width - 1 - border_px &&
         uv.y() <= intr_.height - 1 - border_px;
}

}  // namespace vi_ekf_slam
