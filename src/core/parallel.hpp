#pragma once
// Internal: run per-thread workers over a range of items (not part of the public API).

#include <algorithm>
#include <atomic>
#include <exception>
#include <system_error>
#include <thread>
#include <vector>

namespace leeway::detail {

//! Calls make_worker() once per thread (for per-thread state such as an mjData) and the returned
//! callable for every item in [0, n), items handed out in order from a shared counter. The first
//! exception of any thread is rethrown after all threads joined. Results must not depend on which
//! thread ran an item. When the system refuses to create a thread, the threads created so far (at
//! least the calling one) run every item.
template <class MakeWorker>
void parallel_for(int n, int threads, MakeWorker make_worker) {
  const int workers = std::max(1, std::min(threads, n));
  std::atomic<int> next{0};
  std::vector<std::exception_ptr> errors(static_cast<size_t>(workers));
  auto run = [&](int worker) {
    try {
      auto item_fn = make_worker();
      for (int i = next++; i < n; i = next++) item_fn(i);
    } catch (...) {
      errors[static_cast<size_t>(worker)] = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < workers; ++t) {
    // A thread the system cannot create (EAGAIN: a process or memory limit) leaves its items to the
    // threads that exist: fewer workers, the same results.
    try {
      pool.emplace_back(run, t);
    } catch (const std::system_error&) {
      break;
    }
  }
  run(0);
  for (auto& t : pool) t.join();
  for (auto& e : errors)
    if (e) std::rethrow_exception(e);
}

}  // namespace leeway::detail
