#include "vi_ekf_slam/io/datasets.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/core.hpp>
#include <sstream>
#include <stdexcept>

namespace vi_ekf_slam::io {

namespace {

std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string item;
  while (std::getline(ss, item, sep)) out.push_back(item);
  if (!line.empty() && line.back() == sep) out.emplace_back();
  return out;
}

double toDouble(const std::string& s, const std::string& where) {
  try {
    size_t used = 0;
    const double v = std::stod(s, &used);
    if (used != s.size() && s.find_first_not_of(" \r", used) != std::string::npos) throw std::invalid_argument(s);
    return v;
  } catch (const std::logic_error&) {
    throw std::runtime_error(where + ": '" + s + "' is not a number");
  }
}

/// Reads a numeric CSV: '#' lines skipped, every row must have at least `cols` numbers.
std::vector<std::vector<double>> readNumericCsv(const std::string& path, size_t cols) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open '" + path + "'");
  std::vector<std::vector<double>> rows;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty() || line[0] == '#' || line == "\r") continue;
    const auto f = split(line, ',');
    if (f.size() < cols)
      throw std::runtime_error(path + ":" + std::to_string(n) + ": expected " + std::to_string(cols) + " columns");
    std::vector<double> r;
    for (size_t i = 0; i < cols; ++i) r.push_back(toDouble(f[i], path + ":" + std::to_string(n)));
    rows.push_back(r);
  }
  return rows;
}

cv::FileStorage openYaml(const std::string& path) {
  cv::FileStorage fs;
  try {
    fs.open(path, cv::FileStorage::READ);
  } catch (const cv::Exception& e) {
    throw std::runtime_error("cannot parse '" + path + "': " + e.what());
  }
  if (!fs.isOpened()) throw std::runtime_error("cannot open '" + path + "'");
  return fs;
}

}  // namespace

AslCamera readAslCamera(const std::string& path) {
  cv::FileStorage fs = openYaml(path);
  AslCamera c;
  std::vector<double> intr, dist, T, res;
  fs["intrinsics"] >> intr;
  fs["distortion_coefficients"] >> dist;
  fs["resolution"] >> res;
  fs["T_BS"]["data"] >> T;
  fs["rate_hz"] >> c.rate_hz;
  std::string model;
  fs["distortion_model"] >> model;
  if (intr.size() != 4 || T.size() != 16 || res.size() != 2) {
    throw std::runtime_error(path + ": needs intrinsics [fu fv cu cv], resolution [w h] and T_BS (4x4)");
  }
  c.intrinsics.fx = intr[0];
  c.intrinsics.fy = intr[1];
  c.intrinsics.cx = intr[2];
  c.intrinsics.cy = intr[3];
  c.intrinsics.width = static_cast<int>(res[0]);
  c.intrinsics.height = static_cast<int>(res[1]);
  if (model == "radial-tangential")
    c.intrinsics.model = DistortionModel::kRadTan;
  else if (model == "equidistant")
    c.intrinsics.model = DistortionModel::kEquidistant;
  else
    throw std::runtime_error(path + ": unsupported distortion_model '" + model + "'");
  c.intrinsics.distortion = dist;
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) c.T_b_c.R_b_c(r, k) = T[static_cast<size_t>(4 * r + k)];
    c.T_b_c.p_b_c(r) = T[static_cast<size_t>(4 * r + 3)];
  }
  // Re-orthonormalize the printed rotation.
  c.T_b_c.R_b_c = Quat(c.T_b_c.R_b_c).normalized().toRotationMatrix();
  const std::string err = c.intrinsics.validate();
  if (!err.empty()) throw std::runtime_error(path + ": " + err);
  return c;
}

ImuNoiseParams readAslImuNoise(const std::string& path) {
  cv::FileStorage fs = openYaml(path);
  ImuNoiseParams n;
  fs["gyroscope_noise_density"] >> n.gyro_noise_density;
  fs["gyroscope_random_walk"] >> n.gyro_random_walk;
  fs["accelerometer_noise_density"] >> n.accel_noise_density;
  fs["accelerometer_random_walk"] >> n.accel_random_walk;
  if (!(n.gyro_noise_density > 0) || !(n.accel_noise_density > 0))
    throw std::runtime_error(path + ": missing noise densities");
  return n;
}

ImuNoiseParams eurocMavImuNoise() {
  ImuNoiseParams n;
  n.gyro_noise_density = 2.5e-4;
  n.accel_noise_density = 1.0e-2;
  n.gyro_random_walk = 2.0e-5;
  n.accel_random_walk = 3.0e-3;
  return n;
}

std::vector<AslImage> readAslImages(const std::string& folder) {
  const std::string csv = folder + "/data.csv";
  std::ifstream in(csv);
  if (!in) throw std::runtime_error("cannot open '" + csv + "'");
  std::vector<AslImage> out;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    const auto f = split(line, ',');
    if (f.size() < 2) throw std::runtime_error(csv + ":" + std::to_string(n) + ": expected `timestamp,filename`");
    std::string name = f[1];
    name.erase(std::remove(name.begin(), name.end(), '\r'), name.end());
    out.push_back({toDouble(f[0], csv + ":" + std::to_string(n)) * 1e-9, folder + "/data/" + name});
  }
  return out;
}

std::vector<ImuData> readAslImu(const std::string& csv) {
  std::vector<ImuData> out;
  for (const auto& r : readNumericCsv(csv, 7)) {
    ImuData d;
    d.timestamp = r[0] * 1e-9;
    d.wm = Vec3(r[1], r[2], r[3]);
    d.am = Vec3(r[4], r[5], r[6]);
    out.push_back(d);
  }
  return out;
}

std::vector<AslState> readAslGroundTruth(const std::string& csv) {
  std::vector<AslState> out;
  for (const auto& r : readNumericCsv(csv, 17)) {
    AslState s;
    s.t = r[0] * 1e-9;
    s.p = Vec3(r[1], r[2], r[3]);
    s.q = Quat(r[4], r[5], r[6], r[7]).normalized();
    s.v = Vec3(r[8], r[9], r[10]);
    s.b_g = Vec3(r[11], r[12], r[13]);
    s.b_a = Vec3(r[14], r[15], r[16]);
    out.push_back(s);
  }
  return out;
}

std::vector<StampedPose> toStampedPoses(const std::vector<AslState>& states) {
  std::vector<StampedPose> out;
  for (const auto& s : states) out.push_back({s.t, s.p, s.q, std::nullopt});
  return out;
}

std::vector<StampedPose> readTrajectoryFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open trajectory file '" + path + "'");
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    // ASL (EuRoC) ground truth, state_groundtruth_estimate0/data.csv: 17 comma-separated columns,
    // nanosecond stamps, its header a comment too. A comma-separated TUM file has 8.
    if (std::count(line.begin(), line.end(), ',') >= 16) return toStampedPoses(readAslGroundTruth(path));
    if (line[0] != '#') break;
  }
  return readTum(path);
}

FeatureTrackData readEqvioCsv(const std::string& path, int width, int height) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open '" + path + "'");
  FeatureTrackData d;
  std::map<std::string, double> meta;
  std::map<int, CameraFrame> frames;
  std::vector<std::pair<std::int64_t, Eigen::Vector2d>> pending;
  std::string line;
  int n = 0;
  std::getline(in, line);  // header
  ++n;
  while (std::getline(in, line)) {
    ++n;
    const auto f = split(line, ',');
    if (f.size() < 20) throw std::runtime_error(path + ":" + std::to_string(n) + ": too few columns");
    const std::string where = path + ":" + std::to_string(n);
    if (f[0] == "meta") {
      if (f.size() >= 22) {
        try {
          meta[f[20]] = std::stod(f[21]);
        } catch (const std::logic_error&) {
        }
      }
    } else if (f[0] == "imu") {
      ImuData s;
      s.timestamp = toDouble(f[1], where);
      s.wm = Vec3(toDouble(f[6], where), toDouble(f[7], where), toDouble(f[8], where));
      s.am = Vec3(toDouble(f[9], where), toDouble(f[10], where), toDouble(f[11], where));
      d.imu.push_back(s);
    } else if (f[0] == "vision_feature") {
      const int idx = static_cast<int>(toDouble(f[4], where));
      CameraFrame& fr = frames[idx];
      fr.timestamp = toDouble(f[1], where);
      const Eigen::Vector2d xn(toDouble(f[18], where), toDouble(f[19], where));
      fr.features.push_back({static_cast<std::int64_t>(toDouble(f[5], where)), xn});
    }
  }
  for (const char* k : {"camera_fx", "camera_fy", "camera_cx", "camera_cy", "T_ci_tx", "T_ci_ty", "T_ci_tz", "T_ci_qw",
                        "T_ci_qx", "T_ci_qy", "T_ci_qz"}) {
    if (!meta.count(k)) throw std::runtime_error(path + ": meta row '" + k + "' missing");
  }
  d.camera.width = width;
  d.camera.height = height;
  d.camera.fx = meta["camera_fx"];
  d.camera.fy = meta["camera_fy"];
  d.camera.cx = meta["camera_cx"];
  d.camera.cy = meta["camera_cy"];
  d.camera.model = DistortionModel::kNone;
  // "T_ci" is numerically the camera pose in the IMU frame (R_b_c, p_b_c), see the data README.
  d.T_b_c.R_b_c =
      Quat(meta["T_ci_qw"], meta["T_ci_qx"], meta["T_ci_qy"], meta["T_ci_qz"]).normalized().toRotationMatrix();
  d.T_b_c.p_b_c = Vec3(meta["T_ci_tx"], meta["T_ci_ty"], meta["T_ci_tz"]);
  for (auto& [idx, fr] : frames) {
    for (auto& o : fr.features)
      o.uv = Eigen::Vector2d(d.camera.fx * o.uv.x() + d.camera.cx, d.camera.fy * o.uv.y() + d.camera.cy);
    d.frames.push_back(std::move(fr));
  }
  std::sort(d.imu.begin(), d.imu.end(), [](const ImuData& a, const ImuData& b) { return a.timestamp < b.timestamp; });
  return d;
}

}  // namespace vi_ekf_slam::io
