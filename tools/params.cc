// Prints the files generated from the parameter table (src/ros/param_table.cc): the documented
// YAML, the dynamic_reconfigure definition and the Markdown reference. `make params` writes them
// into config/, cfg/ and docs/; Params.GeneratedFilesAreCurrent fails while a copy is stale.
#include <iostream>

#include "cli.h"
#include "vi_ekf_slam/ros/param_table.h"

int main(int argc, char** argv) {
  namespace po = vi_ekf_slam::cli::po;
  const std::string usage = "vi_ekf_slam_params --yaml | --cfg | --markdown";
  po::options_description options("options");
  options.add_options()("yaml", "config/vi_ekf_slam.yaml: every parameter with its default, unit and range")(
      "cfg",
      "cfg/EkfSlamReconfigure.cfg: the dynamic_reconfigure definition of the parameters that can change while running")(
      "markdown", "docs/parameters.md: the reference table");
  const po::variables_map vm =
      vi_ekf_slam::cli::parse(argc, argv, usage, "Prints a file generated from the node's parameter table.", options);
  if (vm.count("yaml") + vm.count("cfg") + vm.count("markdown") != 1) {
    vi_ekf_slam::cli::fail(usage, "choose exactly one of --yaml, --cfg, --markdown");
  }
  using namespace vi_ekf_slam::glue;
  std::cout << (vm.count("yaml") ? documentedYaml() : vm.count("cfg") ? reconfigureCfg() : parameterReference());
  return 0;
}
