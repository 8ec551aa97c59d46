// The parallel runner (parallel.hpp) and `tactile sim --trials K --jobs J`:
// results in index order whatever the number of workers, jobs really run at
// the same time, a failing job stops the hand-out and its exception (the
// lowest index) reaches the caller; and the trials of jobs = 2 write the same
// bytes as jobs = 1 for the same seeds.
#include <gtest/gtest.h>

#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "tactile_cli/parallel.hpp"
#include "tactile_cli/sim_run.hpp"

namespace fs = std::filesystem;

namespace {

const fs::path kConfig = TACTILE_CONFIG_DIR;

fs::path fresh_dir(const std::string& name) {
  fs::path p = fs::temp_directory_path() / ("tactile_parallel_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  return p;
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Every regular file under `root`, by relative path -> contents.
std::map<std::string, std::string> tree(const fs::path& root) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (e.is_regular_file()) out[fs::relative(e.path(), root).string()] = read_file(e.path());
  }
  return out;
}

/// A metrics.json without its wall-clock figures (they differ between any
/// two runs, serial or not), dumped again the way run_sim writes it.
std::string without_wall_clock(const std::string& text) {
  nlohmann::json m = nlohmann::json::parse(text);
  auto strip = [](nlohmann::json& j) {
    j.erase("wall_time_s");
    j.erase("real_time_factor");
  };
  strip(m);
  if (m.contains("per_trial")) {
    for (auto& t : m["per_trial"]) strip(t);
  }
  if (m.contains("statistics")) strip(m["statistics"]);
  return m.dump(2) + "\n";
}

}  // namespace

// OpenBLAS's thread pool (loaded through OpenCV's core and the GPIS solves) is stopped, and a
// threaded BLAS call afterwards starts it again and computes the right product.
extern "C" void dgemm_(const char*, const char*, const int*, const int*, const int*, const double*,
                       const double*, const int*, const double*, const int*, const double*, double*,
                       const int*) __attribute__((weak));

TEST(ReleaseBlasThreads, StopsOpenBlasPoolWhichComesBackOnUse) {
  auto threads = [] {
    return std::distance(fs::directory_iterator("/proc/self/task"), fs::directory_iterator{});
  };
  const auto before = threads();
  if (!tactile_cli::release_blas_threads() || dgemm_ == nullptr) GTEST_SKIP() << "OpenBLAS is not loaded";
  const auto after = threads();
  if (tactile_cli::available_cores() > 1 && std::getenv("OPENBLAS_NUM_THREADS") == nullptr) {
    EXPECT_LT(after, before) << "the pool's threads are still there";
  }
  const int n = 300;
  std::vector<double> a(n * n), b(n * n), c(n * n, -1.0);
  for (int i = 0; i < n * n; ++i) {
    a[i] = (i % 7) - 3.0;
    b[i] = (i % 5) * 0.5;
  }
  const double one = 1.0, zero = 0.0;
  dgemm_("N", "N", &n, &n, &n, &one, a.data(), &n, b.data(), &n, &zero, c.data(), &n);
  for (const auto& [r, k] : {std::pair{0, 0}, std::pair{17, 123}, std::pair{299, 299}}) {
    double expect = 0.0;  // column-major: C(r, k) = sum_j A(r, j) B(j, k)
    for (int j = 0; j < n; ++j) expect += a[r + j * n] * b[j + k * n];
    EXPECT_DOUBLE_EQ(c[r + k * n], expect) << r << "," << k;
  }
  if (tactile_cli::available_cores() > 1 && std::getenv("OPENBLAS_NUM_THREADS") == nullptr) {
    EXPECT_GT(threads(), after) << "a threaded call did not start the pool again";
  }
}

TEST(Parallel, ResultsComeBackInIndexOrderForAnyNumberOfWorkers) {
  for (int jobs : {1, 2, 3, 0, 64}) {
    SCOPED_TRACE("jobs " + std::to_string(jobs));
    const auto out = tactile_cli::parallel_map(25, jobs, [](size_t i) { return std::to_string(i * i); });
    ASSERT_EQ(out.size(), 25u);
    for (size_t i = 0; i < out.size(); ++i) EXPECT_EQ(out[i], std::to_string(i * i));
  }
  EXPECT_TRUE(tactile_cli::parallel_map(0, 2, [](size_t i) { return i; }).empty());
}

TEST(Parallel, WorkerCountIsClampedAndZeroMeansAllCores) {
  EXPECT_GE(tactile_cli::available_cores(), 1);
  EXPECT_EQ(tactile_cli::resolve_jobs(0, 1000), tactile_cli::available_cores());
  EXPECT_EQ(tactile_cli::resolve_jobs(8, 3), 3);
  EXPECT_EQ(tactile_cli::resolve_jobs(2, 10), 2);
  EXPECT_EQ(tactile_cli::resolve_jobs(2, 0), 1);
  EXPECT_THROW(tactile_cli::resolve_jobs(-1, 3), std::invalid_argument);
}

TEST(Parallel, TwoWorkersRunTwoJobsAtTheSameTime) {
  // Job 0 waits for job 1 to have started (and the other way round): with one
  // worker neither would ever see the other, so the wait would run out.
  std::mutex mu;
  std::condition_variable cv;
  int started = 0;
  const auto saw_other = tactile_cli::parallel_map(2, 2, [&](size_t) {
    std::unique_lock<std::mutex> lk(mu);
    ++started;
    cv.notify_all();
    return cv.wait_for(lk, std::chrono::seconds(30), [&] { return started == 2; });
  });
  EXPECT_TRUE(saw_other[0]);
  EXPECT_TRUE(saw_other[1]);
  // And one thread per worker: jobs = 3 uses three distinct threads.
  std::mutex ids_mu;
  std::set<std::thread::id> ids;
  int waiting = 0;
  tactile_cli::parallel_for(3, 3, [&](size_t) {
    std::unique_lock<std::mutex> lk(ids_mu);
    ids.insert(std::this_thread::get_id());
    ++waiting;
    cv.notify_all();
    cv.wait_for(lk, std::chrono::seconds(30), [&] { return waiting == 3; });
  });
  EXPECT_EQ(ids.size(), 3u);
}

TEST(Parallel, AFailingJobStopsTheHandOutAndItsErrorReachesTheCaller) {
  // One worker: jobs after the failing one never start, as in a serial loop.
  std::atomic<int> ran{0};
  try {
    tactile_cli::parallel_for(10, 1, [&](size_t i) {
      ++ran;
      if (i == 3) throw std::runtime_error("trial 3: bad arena");
    });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "trial 3: bad arena");
  }
  EXPECT_EQ(ran.load(), 4);
  // Two workers, two failures: the caller gets the lowest index's error, and
  // the 100 jobs are not all started.
  ran = 0;
  try {
    tactile_cli::parallel_for(100, 2, [&](size_t i) {
      ++ran;
      if (i == 5 || i == 6) throw std::runtime_error("job " + std::to_string(i));
    });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "job 5");
  }
  EXPECT_LT(ran.load(), 100);
}

TEST(Parallel, SimTrialsOnTwoJobsWriteTheBytesOfASerialRun) {
  // Three seeded trials of the glass-wall protocol (flow-deck estimate, noisy
  // barometers): bag (metadata.yaml and the mcap file, the default storage), trajectory.csv,
  // topview.png and metrics.json of every trial and the aggregate.
  const fs::path dir = fresh_dir("sim");
  auto run = [&](int jobs) {
    tactile_cli::SimOptions o;
    o.scenario = (kConfig / "scenarios" / "whisker_sweep_glass.yaml").string();
    o.out_dir = (dir / ("jobs" + std::to_string(jobs))).string();
    o.config_dir = kConfig.string();
    o.progress = false;
    o.trials = 3;
    o.seed = 7;
    o.jobs = jobs;
    tactile_cli::run_sim(o);
    return tree(o.out_dir);
  };
  const auto serial = run(1);
  const auto parallel = run(2);
  ASSERT_EQ(serial.size(), parallel.size());
  size_t compared = 0;
  for (const auto& [path, bytes] : serial) {
    SCOPED_TRACE(path);
    ASSERT_EQ(parallel.count(path), 1u);
    if (fs::path(path).filename() == "metrics.json") {
      EXPECT_EQ(without_wall_clock(bytes), without_wall_clock(parallel.at(path)));
    } else {
      EXPECT_TRUE(bytes == parallel.at(path)) << bytes.size() << " vs " << parallel.at(path).size() << " bytes";
    }
    ++compared;
  }
  // The aggregate, and per trial: metrics, trajectory, top view, bag metadata and database.
  EXPECT_EQ(compared, 1u + 3u * 5u);
  for (int k = 0; k < 3; ++k) {
    const std::string t = "trial_" + std::to_string(k) + "/";
    for (const char* f : {"metrics.json", "trajectory.csv", "topview.png", "bag/metadata.yaml", "bag/bag_0.mcap"}) {
      EXPECT_EQ(serial.count(t + f), 1u) << t + f;
    }
  }
  // Different seeds per trial: the trials are not copies of one another.
  EXPECT_NE(serial.at("trial_0/trajectory.csv"), serial.at("trial_1/trajectory.csv"));
  fs::remove_all(dir);
}
