// The bench-protocol scenario reader (`tactile stage`): counts and the seed are
// whole numbers checked against their range before use. They were read as
// doubles and cast, so "trials: 2.5" ran 2 trials, "seed: -1" ran seed
// 2^64 - 1 and "trials: 1e12" was undefined behaviour.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "whisker_localization/protocols.hpp"

namespace fs = std::filesystem;

namespace {

std::string error_of(const std::string& yaml) {
  const fs::path path = fs::temp_directory_path() /
      (std::string("wl_protocol_") + ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_bad.yaml");
  {
    std::ofstream f(path);
    f << yaml;
  }
  std::string msg;
  try {
    whisker_localization::run_bench_protocol(path.string());
  } catch (const std::exception& e) {
    msg = e.what();
  }
  fs::remove(path);
  return msg;
}

}  // namespace

TEST(BenchProtocol, CountsMustBeWholeNumbersInRange) {
  std::string msg = error_of("protocol: table1\ntable1: {trials: 2.5}\n");
  EXPECT_NE(msg.find("_bad.yaml: table1.trials: must be an integer in [1, 2147483647], got \"2.5\""), std::string::npos) << msg;
  msg = error_of("protocol: table1\ntable1: {trials: 0}\n");
  EXPECT_NE(msg.find("table1.trials: must be in [1, 2147483647], got 0"), std::string::npos) << msg;
  msg = error_of("protocol: table1\ntable1: {trials: 4294967316}\n");  // 2^32 + 20: no wrap to 20
  EXPECT_NE(msg.find("table1.trials: must be in [1, 2147483647], got 4294967316"), std::string::npos) << msg;
  msg = error_of("protocol: table2\ntable2: {steps: 3}\n");
  EXPECT_NE(msg.find("table2.steps: must be in [4, 2147483647], got 3"), std::string::npos) << msg;
  msg = error_of("protocol: table2\ntable2: {steps: [40]}\n");
  EXPECT_NE(msg.find("table2.steps: must be an integer in [4, 2147483647]"), std::string::npos) << msg;
}

TEST(BenchProtocol, TheSeedIsAnUnsigned64BitInteger) {
  std::string msg = error_of("protocol: table1\nseed: -1\n");
  EXPECT_NE(msg.find("seed: must be an integer in [0, 18446744073709551615], got \"-1\""), std::string::npos) << msg;
  msg = error_of("protocol: table1\nseed: 18446744073709551616\n");  // 2^64
  EXPECT_NE(msg.find("seed: must be in [0, 18446744073709551615], got 18446744073709551616"), std::string::npos) << msg;
  msg = error_of("protocol: table1\nseed: 1e3\n");
  EXPECT_NE(msg.find("seed: must be an integer"), std::string::npos) << msg;
  // A seed above 2^53 (a double would have rounded it) is accepted: the error that
  // follows is the protocol's own.
  msg = error_of("protocol: table9\nseed: 9007199254740993\n");
  EXPECT_EQ(msg.find("seed:"), std::string::npos) << msg;
}
