// Writes a faulty copy of a bag, one fault class at a time (ros/bag_faults.h): clipped IMU samples,
// sensor gaps, a covered lens, NaN IMU samples, dim noisy images, a lossy link.
//
//   vi_ekf_slam_perturb_bag --bag IN --out OUT --fault CLASS [--size X] [--seed N] [--at F]
#include <cmath>
#include <cstdio>
#include <iostream>

#include "cli.h"
#include "vi_ekf_slam/ros/bag_faults.h"

using namespace vi_ekf_slam;

int main(int argc, char** argv) {
  std::string in, out, fault;
  bool list = false, list_moment = false;
  double size = 0.0;
  int seed = 1;
  double at = std::nan("");  // unset
  const std::string usage =
      "vi_ekf_slam_perturb_bag --bag IN --out OUT --fault CLASS [--size X] [--seed N] [--at F] | --list-faults";
  std::string classes;
  for (auto c : glue::allFaultClasses()) {
    classes += (classes.empty() ? "" : " | ") + glue::toString(c) + " (" +
               std::to_string(glue::defaultFaultSize(c)).substr(0, 4) + ")";
  }
  cli::po::options_description opts("options");
  opts.add_options()("list-faults", cli::po::bool_switch(&list), "print the fault classes, one a line, and exit")(
      "list-moment-faults", cli::po::bool_switch(&list_moment),
      "print the classes that act at one moment (--at places them), one a line, and exit")(
      "bag", cli::po::value(&in), "the input bag")("out", cli::po::value(&out), "the faulty copy to write")(
      "fault", cli::po::value(&fault), ("the fault class (default size): " + classes).c_str())(
      "size", cli::po::value(&size), "the fault's size: its period, length [s] or probability (see --help)")(
      "seed", cli::po::value(&seed)->default_value(seed), "random seed")(
      "at", cli::po::value(&at),
      ("the faults of one moment: where the fault starts, a fraction of the bag in [0, 1) (default: the class's "
       "own moment): " +
       glue::momentFaultsList())
          .c_str());
  cli::parse(argc, argv, usage,
             "Writes a faulty copy of a bag: clipped_imu (a sample at the range every SIZE s), sensor_gaps (IMU gaps "
             "of SIZE s, image gaps of 6 SIZE s), covered_lens (black images for SIZE s), nan_imu (a NaN sample every "
             "SIZE s), dim_images (SIZE s of dim noisy images), lossy_link (images dropped with probability SIZE, "
             "duplicated, late), darkness (SIZE s at 5% of the light with the sensor's noise).",
             opts);
  if (list || list_moment) {
    for (auto c : glue::allFaultClasses())
      if (list || glue::actsAtOneMoment(c)) std::printf("%s\n", glue::toString(c).c_str());
    return 0;
  }
  if (in.empty() || out.empty() || fault.empty()) cli::fail(usage, "--bag, --out and --fault are required");
  const auto c = glue::faultClassFromString(fault);
  if (!c) cli::fail(usage, "unknown fault class '" + fault + "'; known: " + classes);
  glue::FaultPlan plan;
  plan.fault = *c;
  plan.size = size > 0.0 ? size : glue::defaultFaultSize(*c);
  plan.seed = static_cast<std::uint64_t>(seed);
  if (!std::isnan(at)) plan.at_fraction = at;
  try {
    const glue::FaultCounts n = glue::perturbBag(in, out, plan);
    std::printf(
        "%s (size %g): IMU %d clipped, %d dropped, %d NaN; images %d dropped, %d black, %d dim, %d duplicated, "
        "%d late -> %s\n",
        fault.c_str(), plan.size, n.imu_clipped, n.imu_dropped, n.imu_nan, n.images_dropped, n.images_black,
        n.images_dim, n.images_duplicated, n.images_late, out.c_str());
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
