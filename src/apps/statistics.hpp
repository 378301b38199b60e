#pragma once
// Internal: the statistics and clocks that tuning and the benchmarks share (not public API).

#include <algorithm>
#include <ctime>
#include <vector>

namespace leeway::detail {

//! Median of `v`; 0 for an empty vector.
inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n == 0 ? 0 : n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

//! Process CPU time [ms] (all threads), for timing single-threaded work on a shared machine.
inline double process_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

}  // namespace leeway::detail
