// The allowed values of every numeric parameter of the core, written once. The structs'
// validate() check them here, and the node's parameter table (src/ros/param_table.cc) takes the
// ranges of the parameters it exposes from here, so the generated YAML, docs and
// dynamic_reconfigure limits are these numbers. Names are the node's parameter names where the
// node has the parameter.
#pragma once

#include <ostream>
#include <string>

namespace vi_ekf_slam {

struct ParamRange {
  double min = 0.0;
  double max = 0.0;
  bool contains(double v) const { return v >= min && v <= max; }  // false for NaN
};

/// Whether `name` has a range here.
bool hasParamRange(const std::string& name);
/// The range of `name`; throws std::out_of_range for a name that has none.
const ParamRange& paramRange(const std::string& name);
/// Appends "name must be in [min, max] (got v)" and a newline to err when v is outside the range
/// of `name` (or not a number).
void checkRange(std::ostream& err, const std::string& name, double v);

}  // namespace vi_ekf_slam
