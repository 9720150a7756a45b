#include "vi_ekf_slam/ros/params.h"

#include <dynamic_reconfigure/Config.h>
#include <ros/param.h>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "vi_ekf_slam/ros/calibration_source.h"
#include "vi_ekf_slam/ros/kalibr_import.h"
#include "vi_ekf_slam/ros/param_table.h"

namespace vi_ekf_slam::glue {

namespace {

/// Reads `name` as a value of the same type as `like`; false if it has another type.
bool readAs(const ParamSource& src, const std::string& name, const ParamValue& like, ParamValue* out) {
  return std::visit(
      [&](const auto& l) {
        std::decay_t<decltype(l)> v;
        if (!src.get(name, v)) return false;
        *out = v;
        return true;
      },
      like);
}

/// What follows from other parameters, and the checks that involve more than one parameter
/// (each core struct's own validate()).
std::string deriveAndValidate(NodeParams& p) {
  std::ostringstream err;
  p.static_init.gravity_mps2 = p.filter.gravity_mps2;
  p.dynamic_init.gravity_mps2 = p.filter.gravity_mps2;
  p.dynamic_init.pixel_noise_px = p.filter.update.pixel_noise_px;
  const NodeOptions& n = p.node;
  if (n.imu_topic.empty() || n.image_topic.empty() || n.camera_info_topic.empty()) {
    err << "imu_topic, image_topic and camera_info_topic must not be empty\n";
  }
  if (n.world_frame.empty()) err << "world_frame must not be empty\n";
  if (n.world_frame == n.body_frame) err << "world_frame and body_frame must differ\n";
  if (n.odom_frame.empty()) err << "odom_frame must not be empty\n";
  if (n.odom_frame == n.base_frame || n.odom_frame == n.body_frame) {
    err << "odom_frame must differ from base_frame and body_frame\n";
  }
  if (!n.map_frame.empty() && n.map_frame == n.odom_frame) err << "map_frame and odom_frame must differ\n";
  if (n.T_b_c.size() != 7) {
    err << "T_b_c must have 7 numbers: x y z qx qy qz qw (got " << n.T_b_c.size() << ")\n";
  } else {
    const double qn = std::sqrt(n.T_b_c[3] * n.T_b_c[3] + n.T_b_c[4] * n.T_b_c[4] + n.T_b_c[5] * n.T_b_c[5] +
                                n.T_b_c[6] * n.T_b_c[6]);
    if (!(std::abs(qn - 1.0) < 1e-3)) err << "T_b_c quaternion must have unit norm (got " << qn << ")\n";
  }
  std::optional<CameraIntrinsics> file_intrinsics;
  const std::string bad_intrinsics = intrinsicsFromOptions(n, &file_intrinsics);
  if (!bad_intrinsics.empty()) err << bad_intrinsics << "\n";
  if (!n.camera_intrinsics.empty() && !n.camera_calibration_file.empty()) {
    err << "camera_intrinsics and camera_calibration_file both give the intrinsics: set one\n";
  }
  if (n.calibration_source == "file" && n.camera_intrinsics.empty() && n.camera_calibration_file.empty()) {
    err << "calibration_source file needs camera_intrinsics, camera_calibration_file or kalibr_camchain\n";
  }
  err << coreProblems(p);
  return err.str();
}

}  // namespace

std::string coreProblems(const NodeParams& p) {
  return p.filter.validate() + p.tracker.validate() + p.dynamic_init.validate() + pipelineParams(p).validate();
}

PipelineParams pipelineParams(const NodeParams& p) {
  PipelineParams out;
  out.static_init = p.static_init;
  out.dynamic_init_enabled = p.dynamic_init_enabled;
  out.dynamic_init = withFilterSettings(p.dynamic_init, p.filter);
  out.max_frame_queue = p.node.max_image_queue;
  out.background_start_attempts = p.background_start_attempts;
  out.reanchor_max_wait_s = p.reanchor_max_wait_s;
  return out;
}

std::vector<std::string> NodeHandleParams::names() const {
  std::vector<std::string> all, out;
  ros::param::getParamNames(all);
  const std::string prefix = nh_.getNamespace() + "/";
  for (const auto& n : all) {
    if (n.rfind(prefix, 0) != 0) continue;
    const std::string rest = n.substr(prefix.size());
    const std::string top = rest.substr(0, rest.find('/'));
    if (out.empty() || out.back() != top) out.push_back(top);
  }
  return out;
}

bool NodeHandleParams::get(const std::string& name, double& v) const {
  if (nh_.getParam(name, v)) return true;
  int i;
  if (!nh_.getParam(name, i)) return false;
  v = i;  // an integer literal is a fine double
  return true;
}

YamlParams::YamlParams(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error("cannot read parameter file '" + path + "': " + e.what());
  }
  if (root.IsNull()) return;  // an empty file
  if (!root.IsMap()) throw std::runtime_error("parameter file '" + path + "' is not a map of `name: value`");
  for (const auto& kv : root) values_[kv.first.as<std::string>()] = kv.second;
}

void YamlParams::set(const std::string& name, const std::string& value) {
  try {
    values_[name] = YAML::Load(value);
  } catch (const YAML::Exception&) {
    values_[name] = YAML::Node(value);  // not YAML: the text itself
  }
}

std::vector<std::string> YamlParams::names() const {
  std::vector<std::string> out;
  for (const auto& kv : values_) out.push_back(kv.first);
  return out;
}

namespace {
template <typename T>
bool yamlAs(const YAML::Node& n, T& v) {
  try {
    v = n.as<T>();
    return true;
  } catch (const YAML::Exception&) {
    return false;
  }
}
}  // namespace

bool YamlParams::get(const std::string& name, double& v) const {
  return values_.at(name).IsScalar() && yamlAs(values_.at(name), v);
}
bool YamlParams::get(const std::string& name, int& v) const {
  return values_.at(name).IsScalar() && yamlAs(values_.at(name), v);
}
bool YamlParams::get(const std::string& name, bool& v) const {
  return values_.at(name).IsScalar() && yamlAs(values_.at(name), v);
}
bool YamlParams::get(const std::string& name, std::string& v) const {
  const YAML::Node& n = values_.at(name);
  if (n.IsNull()) {  // `name:` with nothing after it
    v.clear();
    return true;
  }
  return n.IsScalar() && yamlAs(n, v);
}
bool YamlParams::get(const std::string& name, std::vector<double>& v) const {
  return values_.at(name).IsSequence() && yamlAs(values_.at(name), v);
}

std::vector<std::string> rigPresets(const std::string& package_share) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(package_share + "/config/rigs", ec)) {
    if (e.path().extension() == ".yaml") out.push_back(e.path().stem().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string rigFile(const std::string& rig, const std::string& package_share) {
  const bool is_path =
      rig.find('/') != std::string::npos || (rig.size() > 5 && rig.compare(rig.size() - 5, 5, ".yaml") == 0);
  if (is_path) return rig;
  const std::string path = package_share + "/config/rigs/" + rig + ".yaml";
  if (std::filesystem::exists(path)) return path;
  std::string known;
  for (const std::string& p : rigPresets(package_share)) known += " " + p;
  throw std::runtime_error("no rig preset '" + rig + "' (presets:" + known + "; or give the path of a rig file)");
}

std::vector<std::string> LayeredParams::names() const {
  std::vector<std::string> out = top_.names();
  for (const std::string& n : below_.names()) {
    if (!top_.has(n)) out.push_back(n);
  }
  return out;
}

namespace {

/// The values of the Kalibr files named in `source` (kalibr_camchain, kalibr_imu), or why not. They
/// replace the parameters they set: the file is the calibration.
YamlParams kalibrValues(const ParamSource& source, std::ostringstream& err) {
  YamlParams out;
  std::string camchain, imu;
  if (source.has("kalibr_camchain")) source.get("kalibr_camchain", camchain);
  if (source.has("kalibr_imu")) source.get("kalibr_imu", imu);
  if (camchain.empty() && imu.empty()) return out;
  try {
    for (const auto& [name, value] : importKalibr(camchain, imu).params) out.set(name, value);
  } catch (const std::exception& e) {
    err << e.what() << "\n";
  }
  return out;
}

}  // namespace

std::string loadParams(const ParamSource& explicit_source, NodeParams* out) {
  NodeParams p;
  std::ostringstream err;
  const YamlParams kalibr = kalibrValues(explicit_source, err);
  const LayeredParams source(kalibr, explicit_source);
  for (const std::string& name : source.names()) {
    if (findParam(name)) continue;
    const std::string near = closestParamName(name);
    err << "unknown parameter '" << name << "'" << (near.empty() ? "" : " (did you mean '" + near + "'?)") << "\n";
  }
  for (const ParamSpec& s : paramTable()) {
    if (!source.has(s.name)) continue;
    ParamValue v;
    const ParamValue d = s.defaultValue();
    if (!readAs(source, s.name, d, &v)) {
      err << s.name << " has the wrong type (expected " << (d.index() == 4 ? "a list of numbers" : "a value like ")
          << (d.index() == 4 ? "" : toYaml(d)) << ")\n";
      continue;
    }
    const std::string bad = s.check(v);
    if (!bad.empty()) {
      err << bad << "\n";
      continue;
    }
    s.set(p, v);
  }
  err << deriveAndValidate(p);
  *out = p;
  return err.str();
}

std::string describeParams(const NodeParams& p) {
  std::ostringstream s;
  s << "vi_ekf_slam parameters:";
  for (const ParamSpec& spec : paramTable()) {
    s << "\n  " << spec.name << ": " << toYaml(spec.get(p));
    if (!spec.unit.empty()) s << " [" << spec.unit << "]";
  }
  return s.str();
}

EkfSlamReconfigureConfig toReconfigure(const NodeParams& p) {
  EkfSlamReconfigureConfig c = EkfSlamReconfigureConfig::__getDefault__();
  dynamic_reconfigure::Config msg;
  c.__toMessage__(msg);
  for (auto& b : msg.bools) b.value = std::get<bool>(findParam(b.name)->get(p));
  for (auto& i : msg.ints) i.value = std::get<int>(findParam(i.name)->get(p));
  for (auto& d : msg.doubles) d.value = std::get<double>(findParam(d.name)->get(p));
  for (auto& s : msg.strs) s.value = std::get<std::string>(findParam(s.name)->get(p));
  c.__fromMessage__(msg);
  return c;
}

std::string applyReconfigure(const EkfSlamReconfigureConfig& c, NodeParams* p) {
  NodeParams candidate = *p;
  std::ostringstream err;
  dynamic_reconfigure::Config msg;
  c.__toMessage__(msg);
  auto apply = [&](const std::string& name, const ParamValue& v) {
    const ParamSpec* s = findParam(name);
    if (!s || !s->dynamic) {
      err << name << " cannot change while running\n";
      return;
    }
    const std::string bad = s->check(v);
    if (bad.empty())
      s->set(candidate, v);
    else
      err << bad << "\n";
  };
  for (const auto& b : msg.bools) apply(b.name, ParamValue(static_cast<bool>(b.value)));
  for (const auto& i : msg.ints) apply(i.name, ParamValue(static_cast<int>(i.value)));
  for (const auto& d : msg.doubles) apply(d.name, ParamValue(d.value));
  for (const auto& s : msg.strs) apply(s.name, ParamValue(s.value));
  err << deriveAndValidate(candidate);
  if (err.str().empty()) *p = candidate;
  return err.str();
}

}  // namespace vi_ekf_slam::glue
