#pragma once
// Internal: the seeded random streams of the CF and the sampled safety mode (not public API).

#include <Eigen/Core>
#include <cstdint>
#include <random>

namespace leeway::detail {

//! SplitMix64: decorrelates the seeds of per-window (or per-segment) streams.
inline std::uint64_t splitmix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

//! A uniform double in [0, 1) from the top 53 bits: the same on every standard library.
inline double unit(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

//! One configuration as `leeway cf` draws it at path parameter t of a segment: every joint uniform
//! between the lower and upper bounds interpolated linearly between the ends a and b. Writes `q`.
inline void draw_in_segment(const Eigen::VectorXd& lower_a, const Eigen::VectorXd& upper_a,
                            const Eigen::VectorXd& lower_b, const Eigen::VectorXd& upper_b, double t,
                            std::mt19937_64& rng, Eigen::VectorXd& q) {
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    const double lo = lower_a[i] + t * (lower_b[i] - lower_a[i]);
    const double hi = upper_a[i] + t * (upper_b[i] - upper_a[i]);
    q[i] = lo + (hi - lo) * unit(rng);
  }
}

}  // namespace leeway::detail
