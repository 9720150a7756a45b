// Which input the node is waiting on, by its resolved topic. A topic that matches nothing (a remap
// or rig file naming another topic than the driver's) looks like a node that does nothing; this
// names it: an input that stays silent while another arrives, or every input silent since the
// start. Times are given by the caller (seconds on any monotonic clock), so it is tested without one.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace vi_ekf_slam::glue {

class InputWatch {
 public:
  struct Input {
    std::string name;   ///< as the node calls it: "imu", "image", "camera_info"
    std::string topic;  ///< the resolved topic it is subscribed to
    std::string remap;  ///< how to point it elsewhere, e.g. "image:=YOUR_TOPIC or ~image_topic"
  };

  /// silence_s: how long an input may stay silent before it is named [s]; start_s: now.
  InputWatch(std::vector<Input> inputs, double silence_s, double start_s);

  void arrived(size_t input, double now_s);
  /// An input that is not needed (camera_info while the intrinsics come from a file) is never named.
  void setNeeded(size_t input, bool needed);

  /// "" or what the node waits on: the silent inputs with their topics and how long, and the
  /// inputs that do arrive meanwhile.
  std::string waitingOn(double now_s) const;

  const std::vector<Input>& inputs() const { return inputs_; }

 private:
  std::vector<Input> inputs_;
  std::vector<std::optional<double>> last_;
  std::vector<bool> needed_;
  double silence_s_, start_s_;
};

}  // namespace vi_ekf_slam::glue
