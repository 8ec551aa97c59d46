#include "whisker_driver/bag_source.hpp"

#include <cmath>
#include <stdexcept>

#include "tactile_msgs/cdr/serialization.hpp"

namespace whisker_driver {

BagSource::BagSource(const std::string& path, const std::string& topic)
    : reader_(path), path_(path), topic_(topic) {
  const tactile_bag::TopicInfo* info = reader_.find_topic(topic);
  if (info == nullptr) {
    throw std::runtime_error("bag " + path + ": no topic " + topic);
  }
  const std::string type = tactile_msgs::cdr::MessageTraits<WhiskerPressure>::type_name;
  if (info->type != type) {
    throw std::runtime_error("bag " + path + ": topic " + topic + " has type " + info->type +
                             ", expected " + type);
  }
  reader_.set_topic_filter({topic});
  have_next_ = fetch();
  done_ = !have_next_;
}

bool BagSource::fetch() { return reader_.read_next(next_); }

void BagSource::poll(int64_t now_ns, std::vector<WhiskerPressure>& out) {
  std::vector<int64_t> receive_ns;
  poll_received(now_ns, out, receive_ns);
}

void BagSource::poll_received(int64_t now_ns, std::vector<WhiskerPressure>& out, std::vector<int64_t>& receive_ns) {
  if (!have_next_) {
    done_ = true;
    return;
  }
  if (!started_) {
    started_ = true;
    t0_ns_ = now_ns;
    bag_t0_ns_ = next_.timestamp_ns;
  }
  for (int n = 0; n < kMaxMessagesPerPoll && have_next_; ++n) {
    if (next_.timestamp_ns - bag_t0_ns_ > now_ns - t0_ns_) break;
    WhiskerPressure msg;
    bool ok = true;
    try {
      tactile_msgs::cdr::deserialize(next_.data.data(), next_.data.size(), msg);
    } catch (const std::exception&) {
      ok = false;
    }
    for (int c = 0; ok && c < 3; ++c) {
      const double p = msg.pressure[c];
      if (!std::isfinite(p) || p < kMinPressurePa || p > kMaxPressurePa) ok = false;
      const double t = msg.temperature[c];
      if (std::isinf(t) || (std::isfinite(t) && (t < kMinTemperatureC || t > kMaxTemperatureC))) ok = false;
    }
    if (ok) {
      out.push_back(std::move(msg));
      receive_ns.push_back(next_.timestamp_ns);
    } else {
      ++errors_;
    }
    have_next_ = fetch();
  }
  done_ = !have_next_;
}

}  // namespace whisker_driver
