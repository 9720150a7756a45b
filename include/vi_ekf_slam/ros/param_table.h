// Every parameter of the node, written once: name, type and default (the value in NodeParams{}),
// range, unit, description, and whether it can change while running. Loading (unknown names are
// errors), range checks, the startup echo and dynamic_reconfigure all read this table; the
// documented YAML (config/vi_ekf_slam.yaml), the dynamic_reconfigure definition (cfg/EkfSlamReconfigure.cfg)
// and the parameter reference (docs/parameters.md) are generated from it (`make params`), and a
// test fails when a committed copy differs.
#pragma once

#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "vi_ekf_slam/ros/params.h"

namespace vi_ekf_slam::glue {

using ParamValue = std::variant<bool, int, double, std::string, std::vector<double>>;

struct ParamGroup {
  std::string id;     ///< identifier (dynamic_reconfigure group name)
  std::string title;  ///< heading in the YAML and the reference
};

struct ParamSpec {
  std::string name;
  std::string group;  ///< a ParamGroup id
  std::string unit;   ///< "" when the value has none (a flag, a name, a choice)
  std::string description;
  bool dynamic = false;  ///< can change while running (dynamic_reconfigure)
  /// Numbers: inclusive range (dynamic ones finite, as dynamic_reconfigure needs).
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  /// Strings with fixed choices: value and what it means.
  std::vector<std::pair<std::string, std::string>> choices;
  std::function<ParamValue(const NodeParams&)> get;
  /// Stores a value of the parameter's type, inside its range and choices (checked before).
  std::function<void(NodeParams&, const ParamValue&)> set;

  /// The default: the value in NodeParams{}.
  ParamValue defaultValue() const { return get(NodeParams()); }
  /// "" or why `v` is not a value of this parameter (type, range, choice).
  std::string check(const ParamValue& v) const;
};

const std::vector<ParamGroup>& paramGroups();
const std::vector<ParamSpec>& paramTable();
/// nullptr for a name that is not a parameter.
const ParamSpec* findParam(const std::string& name);
/// The parameter name nearest to `name` (edit distance), or "" when none is close.
std::string closestParamName(const std::string& name);
/// A value as written in YAML (shortest exact decimal for doubles, quoted empty strings).
std::string toYaml(const ParamValue& v);

/// The generated files (see the top of this file).
std::string documentedYaml();
std::string reconfigureCfg();
std::string parameterReference();

}  // namespace vi_ekf_slam::glue
