// `tactile bench`: the whisker bench rig over serial, with two pseudo-terminals
// standing in for the whisker deck's UARTs (text protocol on whisker 1, CSV on
// whisker 2, 50 Hz): pressures and TDORC signals for both whiskers, all recorded.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include "tactile_cli/hardware.hpp"

namespace fs = std::filesystem;

namespace {
struct Pty {
  int master = -1;
  std::string slave;
  Pty() {
    master = ::posix_openpt(O_RDWR | O_NOCTTY);
    if (master < 0 || ::grantpt(master) != 0 || ::unlockpt(master) != 0) return;
    if (const char* n = ::ptsname(master)) slave = n;
  }
  ~Pty() {
    if (master >= 0) ::close(master);
  }
  void write(const std::string& s) const { (void)!::write(master, s.data(), s.size()); }
};
}  // namespace

TEST(BenchRig, SerialWhiskersToSignalsRecorded) {
  Pty left, right;
  if (left.slave.empty() || right.slave.empty()) GTEST_SKIP() << "no pseudo-terminals";
  std::atomic<bool> stop{false};
  std::thread deck([&] {
    for (int k = 0; !stop && k < 200; ++k) {
      char l[160], r[80];
      std::snprintf(l, sizeof l, "P1:%.1f\nP2:%.1f\nP3:%.1f\nT1:25.0\nT2:25.1\nT3:25.2\n", 101325.0 + k,
                    101300.0 + k, 101280.0 + k);
      std::snprintf(r, sizeof r, "%.1f,%.1f,%.1f\n", 100900.0 - k, 100950.0 - k, 100990.0 - k);
      left.write(l);
      right.write(r);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  const fs::path out = fs::temp_directory_path() / ("tactile_bench_" + std::to_string(::getpid()));
  fs::remove_all(out);
  tactile_cli::BenchOptions o;
  o.left_port = left.slave;
  o.right_port = right.slave;
  o.out_dir = out.string();
  o.config_dir = TACTILE_CONFIG_DIR;
  o.duration_s = 1.5;
  const auto m = tactile_cli::run_bench(o);
  stop = true;
  deck.join();
  const auto& p = m["published"];
  ASSERT_TRUE(p.contains("/whisker/left/pressure") && p.contains("/whisker/right/pressure")) << m.dump();
  EXPECT_GT(p["/whisker/left/pressure"].get<uint64_t>(), 40u);  // 50 Hz for 1.5 s
  EXPECT_GT(p["/whisker/right/pressure"].get<uint64_t>(), 40u);
  // Nothing silently dropped: every frame the driver parsed reached TDORC, and
  // TDORC's output plus its counted drops (frames read in the same tick share a
  // stamp: out of order) account for every input.
  for (const char* side : {"left", "right"}) {
    const auto& drv = m["nodes"][std::string("/whisker/") + side + "/whisker_driver"];
    const auto& tdorc = m["nodes"][std::string("/whisker/") + side + "/tdorc_filter"];
    EXPECT_EQ(drv["published"].get<uint64_t>(), tdorc["received"].get<uint64_t>()) << side;
    EXPECT_EQ(tdorc["published"].get<uint64_t>() + tdorc["dropped_out_of_order"].get<uint64_t>() +
                  tdorc["dropped_nonfinite"].get<uint64_t>() + tdorc["dropped_wrong_whisker"].get<uint64_t>(),
              tdorc["received"].get<uint64_t>()) << side;
    EXPECT_EQ(drv["parse_dropped_frames"].get<uint64_t>(), 0u) << side;
  }
  uint64_t total = 0;
  for (const auto& [topic, n] : p.items()) total += n.get<uint64_t>();
  EXPECT_EQ(m["bag_messages"].get<uint64_t>(), total);
  fs::remove_all(out);
}

TEST(BenchRig, MissingPortNamesTheDevice) {
  tactile_cli::BenchOptions o;
  o.left_port = "/dev/does-not-exist-whisker";
  o.out_dir = (fs::temp_directory_path() / ("tactile_bench_missing_" + std::to_string(::getpid()))).string();
  o.config_dir = TACTILE_CONFIG_DIR;
  o.duration_s = 0.1;
  try {
    tactile_cli::run_bench(o);
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/does-not-exist-whisker"), std::string::npos) << e.what();
  }
  fs::remove_all(o.out_dir);
}
