#include "vi_ekf_slam/ros/input_watch.h"

#include <cstdio>

namespace vi_ekf_slam::glue {

InputWatch::InputWatch(std::vector<Input> inputs, double silence_s, double start_s)
    : inputs_(std::move(inputs)),
      last_(inputs_.size()),
      needed_(inputs_.size(), true),
      silence_s_(silence_s),
      start_s_(start_s) {}

void InputWatch::arrived(size_t input, double now_s) { last_.at(input) = now_s; }

void InputWatch::setNeeded(size_t input, bool needed) { needed_.at(input) = needed; }

std::string InputWatch::waitingOn(double now_s) const {
  std::vector<size_t> silent, arriving;
  for (size_t i = 0; i < inputs_.size(); ++i) {
    const double since = now_s - last_[i].value_or(start_s_);
    if (since <= silence_s_) {
      arriving.push_back(i);
    } else if (needed_[i]) {
      silent.push_back(i);
    }
  }
  if (silent.empty()) return "";
  std::string text = "waiting for ";
  for (size_t k = 0; k < silent.size(); ++k) {
    const size_t i = silent[k];
    const double since = now_s - last_[i].value_or(start_s_);
    char secs[32];
    std::snprintf(secs, sizeof(secs), "%.0f s", since);
    text += (k ? "; " : "") + inputs_[i].name + " on " + inputs_[i].topic + " (" +
            (last_[i] ? "silent for " : "nothing received in ") + secs + "; " + inputs_[i].remap + ")";
  }
  if (!arriving.empty()) {
    text += " while ";
    for (size_t k = 0; k < arriving.size(); ++k) text += (k ? ", " : "") + inputs_[arriving[k]].name;
    text += arriving.size() == 1 ? " arrives" : " arrive";
  }
  return text;
}

}  // namespace vi_ekf_slam::glue
