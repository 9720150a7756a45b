// image_transport subscriber of sensor_msgs/CompressedImage (JPEG or PNG) on "<base>/compressed":
// Debian ships image_transport without its plugins package, so users could not set
// `image_transport: compressed` otherwise. Decoding uses OpenCV. It registers under its own name
// (transport "vi_ekf_slam_compressed", lookup "image_transport/vi_ekf_slam_compressed_sub") so it
// never collides with compressed_image_transport's "image_transport/compressed_sub" where that is
// installed; the node maps `image_transport: compressed` to it.
#include <cv_bridge/cv_bridge.h>
#include <image_transport/simple_subscriber_plugin.h>
#include <opencv2/imgcodecs.hpp>
#include <pluginlib/class_list_macros.hpp>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/image_encodings.h>

namespace vi_ekf_slam {

class CompressedSubscriber : public image_transport::SimpleSubscriberPlugin<sensor_msgs::CompressedImage> {
 public:
  std::string getTransportName() const override { return "vi_ekf_slam_compressed"; }

 protected:
  /// The standard topic of compressed images, whatever the transport's own name.
  std::string getTopicToSubscribe(const std::string& base_topic) const override { return base_topic + "/compressed"; }

  void internalCallback(const sensor_msgs::CompressedImageConstPtr& msg, const Callback& user_cb) override {
    cv::Mat img;
    try {
      img = cv::imdecode(cv::Mat(msg->data), cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception& e) {
      ROS_WARN_THROTTLE(1.0, "compressed image: %s", e.what());
      return;
    }
    if (img.empty()) {
      ROS_WARN_THROTTLE(1.0, "compressed image could not be decoded (format '%s')", msg->format.c_str());
      return;
    }
    namespace enc = sensor_msgs::image_encodings;
    std::string encoding;
    if (img.channels() == 1)
      encoding = img.depth() == CV_16U ? enc::MONO16 : enc::MONO8;
    else if (img.channels() == 3)
      encoding = enc::BGR8;
    else if (img.channels() == 4)
      encoding = enc::BGRA8;
    else {
      ROS_WARN_THROTTLE(1.0, "compressed image with %d channels ignored", img.channels());
      return;
    }
    user_cb(cv_bridge::CvImage(msg->header, encoding, img).toImageMsg());
  }
};

}  // namespace vi_ekf_slam

PLUGINLIB_EXPORT_CLASS(vi_ekf_slam::CompressedSubscriber, image_transport::SubscriberPlugin)
