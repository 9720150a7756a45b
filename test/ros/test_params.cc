// The documented parameter file and the built-in defaults are one set of values: a user who runs
// the node without config/vi_ekf_slam.yaml, a tool that builds EkfSlamConfig{} (the study's
// "default"), and the launch files all get the same filter.
#include <gtest/gtest.h>

#include "vi_ekf_slam/ros/params.h"

using namespace vi_ekf_slam::glue;

namespace {

class EmptySource : public ParamSource {
 public:
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
  EXPECT_NE(loadParams(yaml, &p).find("publish_tf must be 'odom', 'none' or 'world' (got 'true')"), std::string::npos);
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
