// Writes the simulator's generated walks (sim/generated_walks.h) as TUM trajectories for the
// study and the suite: OUT/<kind>.txt, 100 Hz, z up, body x forward.
//
//   vi_ekf_slam_make_walks --out DIR [--kinds K1,K2,..|suite|all]
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "cli.h"
#include "vi_ekf_slam/eval/metrics.h"
#include "vi_ekf_slam/sim/generated_walks.h"

using namespace vi_ekf_slam;

int main(int argc, char** argv) {
  std::string out, kinds_arg = "suite";
  const std::string usage = "vi_ekf_slam_make_walks --out DIR [--kinds K1,K2,..|suite|all]";
  cli::po::options_description opts("options");
  opts.add_options()("out", cli::po::value(&out)->required(), "the folder to write <kind>.txt into")(
      "kinds", cli::po::value(&kinds_arg)->default_value(kinds_arg),
      "comma-separated kinds, suite (the suite's default) or all (with the probes)");
  cli::parse(argc, argv, usage, "Writes the simulator's generated walks as TUM files.", opts);
  std::vector<std::string> kinds;
  if (kinds_arg == "suite" || kinds_arg == "all") {
    kinds = sim::generatedWalkKinds(kinds_arg == "suite");
  } else {
    std::stringstream ss(kinds_arg);
    for (std::string k; std::getline(ss, k, ',');) {
      if (!k.empty()) kinds.push_back(k);
    }
  }
  std::filesystem::create_directories(out);
  for (const std::string& kind : kinds) {
    std::vector<io::StampedPose> poses;
    try {
      poses = sim::generatedWalk(kind);
    } catch (const std::invalid_argument& e) {
      std::string known;
      for (const auto& k : sim::generatedWalkKinds(false)) known += " " + k;
      cli::fail(usage, std::string(e.what()) + "; known:" + known);
    }
    const std::string path = out + "/" + kind + ".txt";
    io::writeTum(path, poses, "t x y z qx qy qz qw (vi_ekf_slam_make_walks " + kind + "; z up, body x forward)");
    std::vector<Vec3> p;
    for (const auto& x : poses) p.push_back(x.p);
    std::printf("%s: %.0f s, %.0f m -> %s\n", kind.c_str(), poses.back().t, eval::pathLength(p), path.c_str());
  }
  return 0;
}
