// Host glue of the bridge: a Link + CrazyflieClient + CrazyflieBridgeLogic.
// Connects, starts the whisker and state log blocks, then
//   pump()      receives log data and hands out the decoded messages,
//   on_timer()  sends the logic's setpoint packet,
// with a mutex so that the rclcpp component (receive thread + timer) and the
// `tactile fly` loop use it the same way. Times are the caller's clock [ns].
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <mutex>

#include "crazyflie_bridge/client.hpp"
#include "crazyflie_bridge/crazyflie_bridge_logic.hpp"

namespace crazyflie_bridge {

class BridgeRunner {
 public:
  struct Sinks {
    std::function<void(const tactile_msgs::msg::WhiskerPressure&)> left, right;
    std::function<void(const nav_msgs::msg::Odometry&)> odom;
  };
  struct LatencyStats {
    uint64_t count = 0;
    double sum_s = 0, max_s = 0;  ///< state log sample received -> next setpoint sent
  };

  /// Opens params.uri (or uses `link` if given), connects and starts both log
  /// blocks. Throws UriError / LinkError / ClientError.
  explicit BridgeRunner(const CrazyflieBridgeLogic::Params& params, ClientOptions client_options = {},
                        std::unique_ptr<Link> link = nullptr);

  /// Receives for at most `timeout` (then drains what already arrived),
  /// stamping messages with now_ns(); returns the number of log samples handled.
  static constexpr int kMaxSamplesPerPump = 1000;
  int pump(std::chrono::milliseconds timeout, const std::function<int64_t()>& now_ns, const Sinks& sinks);
  void on_hover_setpoint(const tactile_msgs::msg::HoverSetpoint& msg, int64_t now_ns);
  /// Sends the logic's packet (if any); returns true if one was sent.
  bool on_timer(int64_t now_ns);

  CrazyflieBridgeLogic::Mode mode() const;
  CrazyflieBridgeLogic::Stats logic_stats() const;
  LinkStatistics link_stats() const;
  CrazyflieClient::Stats client_stats() const;
  LatencyStats latency() const;
  const CrazyflieClient& client() const { return *client_; }

 private:
  std::unique_ptr<Link> link_;
  std::unique_ptr<CrazyflieClient> client_;
  CrazyflieBridgeLogic logic_;
  mutable std::mutex mutex_;  ///< guards logic_ and the link's send side
  std::chrono::steady_clock::time_point last_state_rx_{};
  bool state_pending_ = false;
  LatencyStats latency_;
};

}  // namespace crazyflie_bridge
