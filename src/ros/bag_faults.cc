#include "vi_ekf_slam/ros/bag_faults.h"

#include <cmath>
#include <cv_bridge/cv_bridge.h>
#include <limits>
#include <opencv2/core.hpp>
#include <random>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sstream>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <stdexcept>

#include "vi_ekf_slam/ros/bag_replay.h"

namespace vi_ekf_slam::glue {

namespace {

const std::vector<std::pair<FaultClass, std::string>>& names() {
  static const std::vector<std::pair<FaultClass, std::string>> n = {
      {FaultClass::kClippedImu, "clipped_imu"},   {FaultClass::kSensorGaps, "sensor_gaps"},
      {FaultClass::kCoveredLens, "covered_lens"}, {FaultClass::kNanImu, "nan_imu"},
      {FaultClass::kDimImages, "dim_images"},     {FaultClass::kLossyLink, "lossy_link"},
      {FaultClass::kDarkness, "darkness"}};
  return n;
}

bool inside(double t, const std::vector<std::pair<double, double>>& intervals) {
  for (const auto& [a, b] : intervals) {
    if (t >= a && t < b) return true;
  }
  return false;
}

/// The image of a message as mono8 (raw or compressed), or empty.
cv::Mat mono8Of(const rosbag::MessageInstance& m) {
  try {
    if (auto img = m.instantiate<sensor_msgs::Image>()) return cv_bridge::toCvCopy(*img, "mono8")->image;
    if (auto c = m.instantiate<sensor_msgs::CompressedImage>()) return cv_bridge::toCvCopy(*c, "mono8")->image;
  } catch (const std::exception&) {
  }
  return cv::Mat();
}

std_msgs::Header headerOf(const rosbag::MessageInstance& m) {
  if (auto img = m.instantiate<sensor_msgs::Image>()) return img->header;
  if (auto c = m.instantiate<sensor_msgs::CompressedImage>()) return c->header;
  return std_msgs::Header();
}

/// The plan's schedule over a bag of [start, end]: when each fault acts.
struct Schedule {
  std::vector<double> imu_events;  ///< clipped or NaN samples: the first sample at or after each
  std::vector<std::pair<double, double>> imu_gaps, image_gaps, black, dim;
  double dim_light = 1.0;  ///< the share of the light the dim images keep
};

Schedule scheduleOf(const FaultPlan& p, double start, double end, std::mt19937_64& rng) {
  Schedule s;
  const double d = end - start;
  auto at = [&](double fraction, double length) {
    return std::pair{start + fraction * d, start + fraction * d + length};
  };
  switch (p.fault) {
    case FaultClass::kClippedImu:
    case FaultClass::kNanImu: {
      std::uniform_real_distribution<double> jitter(-0.25, 0.25);
      for (double t = start + 0.1 * d; t < end - 0.05 * d; t += p.size)
        s.imu_events.push_back(t + jitter(rng) * p.size);
      break;
    }
    case FaultClass::kSensorGaps:
      s.imu_gaps = {at(0.3, p.size), at(0.5, p.size), at(0.7, p.size)};
      s.image_gaps = {at(0.4, 6.0 * p.size), at(0.8, 6.0 * p.size)};
      break;
    case FaultClass::kCoveredLens:
      s.black = {at(p.at_fraction.value_or(*ownMoment(p.fault)), p.size)};
      break;
    case FaultClass::kDimImages:
    case FaultClass::kDarkness:
      s.dim = {at(p.at_fraction.value_or(*ownMoment(p.fault)), p.size)};
      s.dim_light = p.fault == FaultClass::kDarkness ? 0.05 : 0.2;
      break;
    case FaultClass::kLossyLink:
      break;
  }
  return s;
}

}  // namespace

std::optional<FaultClass> faultClassFromString(const std::string& s) {
  for (const auto& [c, n] : names()) {
    if (n == s) return c;
  }
  return std::nullopt;
}

std::string toString(FaultClass c) {
  for (const auto& [k, n] : names()) {
    if (k == c) return n;
  }
  return "?";
}

std::vector<FaultClass> allFaultClasses() {
  std::vector<FaultClass> all;
  for (const auto& [c, n] : names()) all.push_back(c);
  return all;
}

std::optional<double> ownMoment(FaultClass c) {
  switch (c) {
    case FaultClass::kCoveredLens:
      return 0.5;  // the middle
    case FaultClass::kDimImages:
      return 0.3;
    case FaultClass::kDarkness:
      return 0.5;
    default:
      return std::nullopt;
  }
}

bool actsAtOneMoment(FaultClass c) { return ownMoment(c).has_value(); }

std::string momentFaultsList() {
  std::ostringstream out;
  for (FaultClass c : allFaultClasses()) {
    if (!actsAtOneMoment(c)) continue;
    if (out.tellp() > 0) out << ", ";
    out << toString(c) << " (" << *ownMoment(c) << ")";
  }
  return out.str();
}

double defaultFaultSize(FaultClass c) {
  switch (c) {
    case FaultClass::kClippedImu:
      return 3.0;  // one clipped sample every 3 s
    case FaultClass::kSensorGaps:
      return 0.25;  // IMU gaps of 0.25 s, image gaps of 1.5 s
    case FaultClass::kCoveredLens:
      return 2.0;
    case FaultClass::kNanImu:
      return 2.0;
    case FaultClass::kDimImages:
      return 20.0;
    case FaultClass::kLossyLink:
      return 0.1;
    case FaultClass::kDarkness:
      return 10.0;
  }
  return 0.0;
}

cv::Mat dimmed(const cv::Mat& mono8, double light, double noise_sigma, cv::RNG& rng) {
  cv::Mat noise(mono8.size(), CV_32F), f, out;
  rng.fill(noise, cv::RNG::NORMAL, 0.0, noise_sigma);
  mono8.convertTo(f, CV_32F, light);
  f += noise;
  f.convertTo(out, CV_8U);  // saturating
  return out;
}

FaultCounts perturbBag(const std::string& in, const std::string& out, const FaultPlan& p) {
  if (!(p.size > 0.0)) throw std::runtime_error("the fault's size must be > 0");
  if (p.at_fraction) {
    if (!actsAtOneMoment(p.fault))
      throw std::runtime_error("a moment (at) is for the faults of one moment: " + momentFaultsList());
    if (!(*p.at_fraction >= 0.0 && *p.at_fraction < 1.0)) throw std::runtime_error("the moment (at) must be in [0, 1)");
  }
  const InputTopics topics = chooseInputTopics(in, std::nullopt, std::nullopt, std::nullopt);
  rosbag::Bag src(in, rosbag::bagmode::Read);
  rosbag::View view(src);
  const double start = view.getBeginTime().toSec(), end = view.getEndTime().toSec();
  std::mt19937_64 rng(p.seed);
  const Schedule s = scheduleOf(p, start, end, rng);
  FaultCounts n;
  for (const auto* v : {&s.imu_gaps, &s.image_gaps, &s.black, &s.dim})
    n.intervals.insert(n.intervals.end(), v->begin(), v->end());
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uniform_int_distribution<int> axis(0, 2);
  size_t next_event = 0;
  rosbag::Bag dst(out, rosbag::bagmode::Write);
  for (const rosbag::MessageInstance& m : view) {
    const double t = m.getTime().toSec();
    if (m.getTopic() == topics.imu) {
      auto imu = m.instantiate<sensor_msgs::Imu>();
      if (!imu) continue;
      if (inside(t, s.imu_gaps)) {
        ++n.imu_dropped;
        continue;
      }
      if (next_event < s.imu_events.size() && t >= s.imu_events[next_event]) {
        ++next_event;
        n.intervals.emplace_back(t, t);
        if (p.fault == FaultClass::kNanImu) {
          imu->linear_acceleration.x = imu->angular_velocity.y = std::numeric_limits<double>::quiet_NaN();
          ++n.imu_nan;
        } else {
          // One accelerometer and one gyro axis at the range, with the sign of the sample.
          double* a[3] = {&imu->linear_acceleration.x, &imu->linear_acceleration.y, &imu->linear_acceleration.z};
          double* w[3] = {&imu->angular_velocity.x, &imu->angular_velocity.y, &imu->angular_velocity.z};
          double* ka = a[axis(rng)];
          double* kw = w[axis(rng)];
          *ka = std::copysign(p.accel_range_mps2, *ka);
          *kw = std::copysign(p.gyro_range_radps, *kw);
          ++n.imu_clipped;
        }
      }
      dst.write(m.getTopic(), m.getTime(), imu);
      continue;
    }
    if (m.getTopic() != topics.image) {
      dst.write(m.getTopic(), m.getTime(), m);
      continue;
    }
    if (inside(t, s.image_gaps)) {
      ++n.images_dropped;
      continue;
    }
    if (p.fault == FaultClass::kLossyLink) {
      if (u(rng) < p.size) {
        ++n.images_dropped;
        continue;
      }
      // Late: the image arrives after IMU samples newer than it (its stamp unchanged).
      const double late = u(rng) < 0.5 ? 0.03 * u(rng) : 0.0;
      n.images_late += late > 0.0;
      dst.write(m.getTopic(), m.getTime() + ros::Duration(late), m);
      if (u(rng) < 0.5 * p.size) {
        dst.write(m.getTopic(), m.getTime() + ros::Duration(late + 1e-4), m);
        ++n.images_duplicated;
      }
      continue;
    }
    const bool black = inside(t, s.black), dim = inside(t, s.dim);
    if (!black && !dim) {
      dst.write(m.getTopic(), m.getTime(), m);
      continue;
    }
    cv::Mat img = mono8Of(m);
    if (img.empty()) continue;
    if (black) {
      img.setTo(0);
      ++n.images_black;
    } else {
      img = dimmed(img, s.dim_light, 8.0, cv::theRNG());
      ++n.images_dim;
    }
    dst.write(m.getTopic(), m.getTime(), cv_bridge::CvImage(headerOf(m), "mono8", img).toImageMsg());
  }
  return n;
}

}  // namespace vi_ekf_slam::glue
