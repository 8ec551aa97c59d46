// Replays the WhiskerPressure messages of one topic of a rosbag2 bag
// (tactile_bag, sqlite3 storage, CDR). Node-logic layer, no ROS.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "tactile_bag/bag.hpp"
#include "whisker_driver/sources.hpp"

namespace whisker_driver {

/// Messages are emitted in bag order, paced by their recorded timestamps: a
/// message recorded dt after the first one is emitted by the first poll at or
/// after t0 + dt (t0 = now_ns of the first poll). Messages keep their recorded
/// content (stamps included). Messages that do not decode, or hold non-finite
/// or out-of-range pressures, are dropped and counted in errors().
class BagSource : public WhiskerSource {
 public:
  /// Throws tactile_bag::BagError (missing bag) or std::runtime_error naming
  /// the path and topic (topic missing, wrong type).
  BagSource(const std::string& path, const std::string& topic);
  void poll(int64_t now_ns, std::vector<WhiskerPressure>& out) override;
  /// Receive time of each message: its bag timestamp (when the recorder got it).
  void poll_received(int64_t now_ns, std::vector<WhiskerPressure>& out, std::vector<int64_t>& receive_ns) override;
  bool finished() const override { return done_; }
  uint64_t errors() const override { return errors_; }

  static constexpr int kMaxMessagesPerPoll = 1000;

 private:
  bool fetch();  // reads the next message into next_; false at the end

  tactile_bag::Reader reader_;
  std::string path_, topic_;
  tactile_bag::SerializedMessage next_;
  bool have_next_ = false;
  bool done_ = false;
  bool started_ = false;
  int64_t t0_ns_ = 0;
  int64_t bag_t0_ns_ = 0;
  uint64_t errors_ = 0;
};

}  // namespace whisker_driver
