// One table for every parameter (param_table.h): the documented parameter file, the
// dynamic_reconfigure definition and the reference are generated from it and current; the built-in
// defaults are its defaults (a user who runs the node without config/vi_ekf_slam.yaml, a tool that
// builds EkfSlamConfig{} and the launch files all get the same filter); unknown names, wrong types
// and values out of range are errors.
#include <dynamic_reconfigure/Config.h>
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "vi_ekf_slam/core/param_ranges.h"
#include "vi_ekf_slam/ros/param_table.h"
#include "vi_ekf_slam/ros/params.h"

using namespace vi_ekf_slam;
using namespace vi_ekf_slam::glue;

namespace {

class EmptySource : public ParamSource {
 public:
  std::vector<std::string> names() const override { return {}; }
  bool has(const std::string&) const override { return false; }
  bool get(const std::string&, double&) const override { return false; }
  bool get(const std::string&, int&) const override { return false; }
  bool get(const std::string&, bool&) const override { return false; }
  bool get(const std::string&, std::string&) const override { return false; }
  bool get(const std::string&, std::vector<double>&) const override { return false; }
};

}  // namespace

TEST(Params, DocumentedYamlHoldsTheBuiltInDefaults) {
  NodeParams from_yaml, built_in;
  ASSERT_EQ(loadParams(YamlParams(std::string(VI_EKF_SLAM_SOURCE_DIR) + "/config/vi_ekf_slam.yaml"), &from_yaml), "");
  ASSERT_EQ(loadParams(EmptySource(), &built_in), "");
  EXPECT_EQ(describeParams(from_yaml), describeParams(built_in));
  EXPECT_EQ(describeParams(built_in), describeParams(NodeParams()));
}

TEST(Params, FrameChoicesAreValidated) {
  const std::string file = std::string(VI_EKF_SLAM_SOURCE_DIR) + "/config/vi_ekf_slam.yaml";
  NodeParams p;
  YamlParams yaml(file);
  yaml.set("publish_tf", "true");  // the former boolean
  EXPECT_NE(loadParams(yaml, &p).find("publish_tf must be one of odom, none, world (got 'true')"), std::string::npos);
  YamlParams same(file);
  same.set("base_frame", "odom");
  EXPECT_NE(loadParams(same, &p).find("odom_frame must differ from base_frame"), std::string::npos);
  YamlParams ok(file);
  ok.set("publish_tf", "none");
  ok.set("base_frame", "base_link");
  ok.set("map_frame", "map");
  ASSERT_EQ(loadParams(ok, &p), "");
  EXPECT_EQ(p.node.publish_tf, TfMode::kNone);
  EXPECT_EQ(p.node.base_frame, "base_link");
}

namespace {
std::string fileText(const std::string& relative) {
  std::ifstream in(std::string(VI_EKF_SLAM_SOURCE_DIR) + "/" + relative);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
const std::string kDefaults = std::string(VI_EKF_SLAM_SOURCE_DIR) + "/config/vi_ekf_slam.yaml";
}  // namespace

TEST(Params, TheGeneratedFilesAreCurrent) {
  EXPECT_EQ(fileText("config/vi_ekf_slam.yaml"), documentedYaml()) << "run `make params`";
  EXPECT_EQ(fileText("cfg/EkfSlamReconfigure.cfg"), reconfigureCfg()) << "run `make params`";
  EXPECT_EQ(fileText("docs/parameters.md"), parameterReference()) << "run `make params`";
}

TEST(Params, TheBuiltReconfigureServerHasTheTablesDefaultsAndRanges) {
  // The generated EkfSlamReconfigureConfig (from cfg/EkfSlamReconfigure.cfg) against the table.
  dynamic_reconfigure::Config def, lo, hi;
  EkfSlamReconfigureConfig::__getDefault__().__toMessage__(def);
  EkfSlamReconfigureConfig::__getMin__().__toMessage__(lo);
  EkfSlamReconfigureConfig::__getMax__().__toMessage__(hi);
  size_t dynamic = 0;
  for (const auto& s : paramTable()) dynamic += s.dynamic;
  EXPECT_EQ(def.bools.size() + def.ints.size() + def.doubles.size() + def.strs.size(), dynamic);
  for (size_t i = 0; i < def.doubles.size(); ++i) {
    const ParamSpec* s = findParam(def.doubles[i].name);
    ASSERT_TRUE(s && s->dynamic) << def.doubles[i].name;
    EXPECT_EQ(def.doubles[i].value, std::get<double>(s->defaultValue())) << s->name;
    EXPECT_EQ(lo.doubles[i].value, s->min) << s->name;
    EXPECT_EQ(hi.doubles[i].value, s->max) << s->name;
  }
  for (size_t i = 0; i < def.ints.size(); ++i) {
    const ParamSpec* s = findParam(def.ints[i].name);
    ASSERT_TRUE(s && s->dynamic) << def.ints[i].name;
    EXPECT_EQ(def.ints[i].value, std::get<int>(s->defaultValue())) << s->name;
    EXPECT_EQ(lo.ints[i].value, s->min) << s->name;
    EXPECT_EQ(hi.ints[i].value, s->max) << s->name;
  }
  for (const auto& b : def.bools) EXPECT_EQ(b.value, std::get<bool>(findParam(b.name)->defaultValue())) << b.name;
  for (const auto& t : def.strs) EXPECT_EQ(t.value, std::get<std::string>(findParam(t.name)->defaultValue())) << t.name;
}

TEST(Params, UnknownNamesWrongTypesAndValuesOutOfRangeAreErrors) {
  NodeParams p;
  YamlParams typo(kDefaults);
  typo.set("max_landmark", "10");
  EXPECT_NE(loadParams(typo, &p).find("unknown parameter 'max_landmark' (did you mean 'max_landmarks'?)"),
            std::string::npos);
  YamlParams far(kDefaults);
  far.set("completely_different", "1");
  const std::string e = loadParams(far, &p);
  EXPECT_NE(e.find("unknown parameter 'completely_different'\n"), std::string::npos) << e;
  YamlParams range(kDefaults);
  range.set("pixel_noise_px", "50");
  EXPECT_NE(loadParams(range, &p).find("pixel_noise_px must be in [0.1, 10.0] (got 50.0)"), std::string::npos);
  YamlParams type(kDefaults);
  type.set("max_tracks", "1.5");
  EXPECT_NE(loadParams(type, &p).find("max_tracks has the wrong type"), std::string::npos);
  YamlParams list(kDefaults);
  list.set("T_b_c", "[1, 2]");
  EXPECT_NE(loadParams(list, &p).find("T_b_c must have 7 numbers"), std::string::npos);
  YamlParams choice(kDefaults);
  choice.set("mechanization", "robocentric");
  EXPECT_NE(loadParams(choice, &p)
                .find("mechanization must be one of world_centric, sensor_centric, "
                      "sensor_centric_composition (got 'robocentric')"),
            std::string::npos);
  YamlParams ok(kDefaults);
  ok.set("pixel_noise_px", "2");  // an integer literal is a fine double
  ok.set("mechanization", "world_centric");
  ASSERT_EQ(loadParams(ok, &p), "");
  EXPECT_EQ(p.filter.update.pixel_noise_px, 2.0);
  EXPECT_EQ(p.dynamic_init.pixel_noise_px, 2.0) << "derived from pixel_noise_px";
  EXPECT_EQ(p.filter.mechanization, Mechanization::kWorldCentric);
}

TEST(Params, ReconfigureGoesBothWaysAndRefusesWhatLoadingRefuses) {
  NodeParams p;
  EkfSlamReconfigureConfig c = toReconfigure(p);
  c.mechanization = "world_centric";
  c.max_tracks = 60;
  c.zero_velocity = false;
  c.inverse_depth_sigma = 0.25;
  ASSERT_EQ(applyReconfigure(c, &p), "");
  EXPECT_EQ(p.filter.mechanization, Mechanization::kWorldCentric);
  EXPECT_EQ(p.tracker.max_tracks, 60);
  EXPECT_FALSE(p.filter.zero_velocity.enabled);
  EXPECT_EQ(p.filter.inverse_depth_sigma, 0.25);
  EXPECT_EQ(describeParams(p), [&] {
    NodeParams q;
    EXPECT_EQ(applyReconfigure(toReconfigure(p), &q), "");
    return describeParams(q);
  }());
  const NodeParams before = p;
  c.zero_velocity_moving_parallax_px = 1.0;  // below zero_velocity_max_parallax_px: the core refuses it
  EXPECT_NE(applyReconfigure(c, &p), "");
  EXPECT_EQ(describeParams(p), describeParams(before)) << "a refused update changes nothing";
  c = toReconfigure(p);
  c.detector = "orb";
  EXPECT_NE(applyReconfigure(c, &p).find("detector must be one of shi_tomasi, fast"), std::string::npos);
}

TEST(Params, EveryShippedParameterFileLoads) {
  // Rig and data set files go on top of the defaults, as run_bag rig:= and the launch files do.
  for (const std::string f : {"config/euroc.yaml", "config/sim_hallway.yaml", "config/rigs/dmvio_handheld.yaml",
                              "test/ros/test_config.yaml"}) {
    YamlParams yaml(kDefaults);
    yaml.overlay(YamlParams(std::string(VI_EKF_SLAM_SOURCE_DIR) + "/" + f));
    NodeParams p;
    EXPECT_EQ(loadParams(yaml, &p), "") << f;
  }
}

// A range is written once, in the core (core/param_ranges.h): the table publishes it, and the core
// struct that holds the parameter refuses a value outside it on its own (tools and tests that set
// the structs directly go through no table). For each of the table's parameters with a core range,
// a value just past its maximum and just below its minimum must be named by the core's validate().
TEST(Params, EachCoreRangeIsWrittenOnceAndTheCoreRefusesValuesOutsideIt) {
  int checked = 0;
  for (const ParamSpec& spec : paramTable()) {
    if (!hasParamRange(spec.name)) continue;
    const ParamRange& r = paramRange(spec.name);
    EXPECT_EQ(spec.min, r.min) << spec.name;
    EXPECT_EQ(spec.max, r.max) << spec.name;
    if (spec.name.rfind("static_", 0) == 0) continue;  // the static initializer has no validate()
    const bool is_int = std::holds_alternative<int>(spec.defaultValue());
    for (const double outside : {r.max + (is_int ? 1.0 : std::max(1e-6, std::abs(r.max) * 0.01)),
                                 r.min - (is_int ? 1.0 : std::max(1e-9, std::abs(r.min) * 0.01))}) {
      NodeParams p;
      if (is_int) {
        spec.set(p, ParamValue(static_cast<int>(outside)));
      } else {
        spec.set(p, ParamValue(outside));
      }
      const std::string err = coreProblems(p);
      EXPECT_NE(err.find(spec.name), std::string::npos) << spec.name << " = " << outside << " not refused: " << err;
    }
    ++checked;
  }
  EXPECT_GT(checked, 50);
}
