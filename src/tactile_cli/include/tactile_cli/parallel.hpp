// Parallel runner for independent jobs (seeded trials of `tactile sim`, the
// scenarios of a sweep, the seeds a scenario test flies): N jobs on J worker
// threads of this process, results collected in index order, so the caller
// sees exactly what a serial loop would have produced.
//
// Threads, not worker processes: a job of the host owns everything it touches
// (its Host, Bus, Executor, SimLogic with its seeded RNG streams, node logics,
// bag Writer with its own sqlite connection, output directory). The process-wide
// state the jobs share is read-only or thread-safe: function-local `static const`
// tables (initialised once, C++11), the environment (getenv, never set),
// sqlite3 (Debian's libsqlite3 is built with SQLITE_THREADSAFE=1; one connection
// per Writer), OpenCV drawing and PNG encoding on per-call images, PCL filters on
// per-call clouds, yaml-cpp / nlohmann::json on per-call documents. Results come
// back as values and exceptions as exceptions (no files or pipes to parse), and
// forking a process that may already run threads (OpenCV's pool, the bag's
// flusher) would be unsafe. test_parallel.cpp and test_sim.cpp check that the
// outputs of jobs = 2 are byte-identical to jobs = 1.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

namespace tactile_cli {

/// Cores this process may run on (its CPU affinity mask; at least 1): what
/// `--jobs 0` ("all cores", the default of the commands) means.
int available_cores();

/// Workers for `jobs` requested and `n` jobs: jobs == 0 -> available_cores();
/// never more than n (at least 1). Throws std::invalid_argument for jobs < 0.
int resolve_jobs(int jobs, size_t n);

/// Runs job(0) ... job(n - 1) on resolve_jobs(jobs, n) worker threads, each
/// worker taking the next index when it is free. With one worker every job
/// runs on the calling thread, in order. If jobs throw, no further job is
/// started, the running ones finish, and the exception of the lowest index is
/// rethrown (the outputs of finished jobs stay where the jobs put them).
void parallel_for(size_t n, int jobs, const std::function<void(size_t)>& job);

/// Stops OpenBLAS's idle thread pool, if OpenBLAS is loaded (through OpenCV's core and the
/// GPIS solves); returns whether it did. OpenBLAS starts its pool when the library loads, and
/// each pool thread spins (sched_yield) for its thread timeout before it sleeps: ~0.11 s of
/// CPU in every process (measured 2026-11-24 on this workspace's 2-core VM: 0.114 s of CPU
/// in a process that only sleeps, 0.004 s after this call), which is 7 % of a 10-trial
/// `tactile sim` and is taken from the trials' workers under `--jobs 2` or on one core.
/// The pool is started again by OpenBLAS itself on the first threaded BLAS call (a GPIS
/// update at the ground-station budget), so nothing is lost. Without OpenBLAS (another
/// BLAS, or none) it does nothing and returns false.
bool release_blas_threads();

/// parallel_for that collects job(i)'s return value at index i.
template <class F>
auto parallel_map(size_t n, int jobs, F&& job) -> std::vector<std::invoke_result_t<F&, size_t>> {
  using R = std::invoke_result_t<F&, size_t>;
  std::vector<std::optional<R>> slots(n);
  parallel_for(n, jobs, [&](size_t i) { slots[i].emplace(job(i)); });
  std::vector<R> out;
  out.reserve(n);
  for (auto& s : slots) out.push_back(std::move(*s));
  return out;
}

}  // namespace tactile_cli
