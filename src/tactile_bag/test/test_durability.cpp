// Crash durability: a child process records and is SIGKILLed; the bag must still
// open and hold every message written more than 1 s before the kill.
//
// Clock: CLOCK_MONOTONIC is system-wide, so the child stamps each message with the
// monotonic time at which write() returned and the parent compares those stamps
// with the monotonic time of the kill.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <thread>

#include "tactile_bag/bag.hpp"

namespace fs = std::filesystem;

namespace {

int64_t mono_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

std::string temp_bag(const char* name) {
  std::random_device rd;
  return (fs::temp_directory_path() /
          ("tactile_bag_dur_" + std::to_string(::getpid()) + "_" + std::to_string(rd()) + "_" +
           name))
      .string();
}

// Child: write message i with payload = i (8 bytes) and timestamp = mono time after the
// write; `burst` messages then idle forever, or (burst == 0) write every ms forever.
[[noreturn]] void child_main(const std::string& dir, int burst, const tactile_bag::WriterOptions& options) {
  try {
    tactile_bag::Writer w(options);
    w.open(dir);
    tactile_bag::TopicInfo t;
    t.name = "/counter";
    t.type = "std_msgs/msg/UInt64";
    w.create_topic(t);
    for (uint64_t i = 0;; ++i) {
      if (burst > 0 && i >= static_cast<uint64_t>(burst)) {
        for (;;) ::pause();
      }
      uint8_t payload[8];
      std::memcpy(payload, &i, 8);
      w.write("/counter", mono_ns(), payload, 8);
      if (burst == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  } catch (...) {
    ::_exit(3);
  }
}

struct KillResult {
  int64_t kill_ns;
  std::string dir;
};

KillResult run_and_kill(const char* name, int burst, std::chrono::milliseconds run_for,
                        const tactile_bag::WriterOptions& options = {}) {
  const std::string dir = temp_bag(name);
  const pid_t pid = ::fork();
  if (pid == 0) child_main(dir, burst, options);
  EXPECT_GT(pid, 0);
  std::this_thread::sleep_for(run_for);
  const int64_t kill_ns = mono_ns();
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFSIGNALED(status)) << "child exited early with status " << status;
  return {kill_ns, dir};
}

}  // namespace

TEST(Durability, KilledWhileWritingKeepsAllButTheLastSecond) {
  const auto res = run_and_kill("busy", 0, std::chrono::milliseconds(2500));
  ASSERT_TRUE(fs::exists(res.dir + "/metadata.yaml"));  // written at open
  tactile_bag::Reader r(res.dir);
  EXPECT_FALSE(r.metadata_complete());  // recovered from the database
  EXPECT_GT(r.message_count(), 0u);
  tactile_bag::SerializedMessage m;
  uint64_t expected = 0;
  int64_t last_ts = 0;
  while (r.read_next(m)) {
    ASSERT_EQ(m.data.size(), 8u);
    uint64_t v = 0;
    std::memcpy(&v, m.data.data(), 8);
    ASSERT_EQ(v, expected) << "gap in the recovered messages";
    ++expected;
    last_ts = m.timestamp_ns;
  }
  EXPECT_EQ(expected, r.message_count());
  // Messages are written in counter order with increasing stamps and no gap, so
  // everything stamped before last_ts is present. Require last_ts within 1 s of the kill.
  EXPECT_GE(last_ts, res.kill_ns - 1000000000LL)
      << "lost " << static_cast<double>(res.kill_ns - last_ts) * 1e-9 << " s before the kill";
  fs::remove_all(res.dir);
}

TEST(Durability, KilledWhileIdleKeepsEverything) {
  // 200 messages, then the writer is idle: the background thread must commit them.
  const auto res = run_and_kill("idle", 200, std::chrono::milliseconds(1500));
  tactile_bag::Reader r(res.dir);
  EXPECT_EQ(r.message_count(), 200u);
  EXPECT_EQ(r.message_count("/counter"), 200u);
  ASSERT_EQ(r.topics().size(), 1u);
  EXPECT_EQ(r.topics()[0].type, "std_msgs/msg/UInt64");
  fs::remove_all(res.dir);
}

TEST(Durability, SizeOnlyCommitsKeepEveryFullChunkOfAKilledRecording) {
  // flush_interval 0 (reproducible recordings): nothing is committed by wall time, so the
  // idle writer keeps its last partial chunk in memory, and a kill loses it, but no more.
  // sqlite3: 250 messages of 8 bytes, a transaction per 800 bytes -> exactly 200 survive.
  tactile_bag::WriterOptions o;
  o.flush_interval = std::chrono::milliseconds(0);
  o.chunk_size = 800;
  {
    const auto res = run_and_kill("size_sqlite", 250, std::chrono::milliseconds(900), o);
    tactile_bag::Reader r(res.dir);
    EXPECT_EQ(r.message_count(), 200u);
    fs::remove_all(res.dir);
  }
  // mcap: a chunk goes to the file once its records reach 800 bytes: at most 21 messages of
  // 39 bytes (every chunk also holds the channel record, so fewer): the messages of the last
  // partial chunk (at most 21) are lost, and some are (242 of 250 here).
  o.storage = "mcap";
  {
    const auto res = run_and_kill("size_mcap", 250, std::chrono::milliseconds(900), o);
    tactile_bag::Reader r(res.dir);
    EXPECT_LT(r.message_count(), 250u);
    EXPECT_GE(r.message_count(), 250u - 21u);
    fs::remove_all(res.dir);
  }
}
