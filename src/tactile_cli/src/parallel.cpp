#include "tactile_cli/parallel.hpp"

#include <sched.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <stdexcept>
#include <string>
#include <system_error>
#include <thread>

// OpenBLAS's own shutdown of its thread pool (blas_server.c; exported, what its fork handler
// calls). Weak: absent when no OpenBLAS is loaded.
extern "C" int blas_thread_shutdown_(void) __attribute__((weak));

namespace tactile_cli {

bool release_blas_threads() {
  if (blas_thread_shutdown_ == nullptr) return false;
  blas_thread_shutdown_();
  return true;
}

int available_cores() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0) {
    const int n = CPU_COUNT(&set);
    if (n > 0) return n;
  }
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

int resolve_jobs(int jobs, size_t n) {
  if (jobs < 0) throw std::invalid_argument("--jobs must be >= 0 (0: all cores), got " + std::to_string(jobs));
  const size_t wanted = jobs == 0 ? static_cast<size_t>(available_cores()) : static_cast<size_t>(jobs);
  return static_cast<int>(std::max<size_t>(1, std::min(wanted, n)));
}

void parallel_for(size_t n, int jobs, const std::function<void(size_t)>& job) {
  const int workers = resolve_jobs(jobs, n);
  if (n == 0) return;
  if (workers == 1) {
    for (size_t i = 0; i < n; ++i) job(i);
    return;
  }
  std::vector<std::exception_ptr> errors(n);
  std::atomic<size_t> next{0};
  std::atomic<bool> failed{false};
  auto work = [&] {
    for (;;) {
      if (failed.load()) return;
      const size_t i = next.fetch_add(1);
      if (i >= n) return;
      try {
        job(i);
      } catch (...) {
        errors[i] = std::current_exception();
        failed.store(true);
      }
    }
  };
  std::vector<std::thread> threads;
  threads.reserve(static_cast<size_t>(workers - 1));
  try {
    for (int w = 1; w < workers; ++w) threads.emplace_back(work);
  } catch (const std::system_error&) {
    // No more threads to be had: the workers that started (and this thread) do every job.
  }
  work();  // the calling thread is one of the workers
  for (auto& t : threads) t.join();
  for (const auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

}  // namespace tactile_cli
