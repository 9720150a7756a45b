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
