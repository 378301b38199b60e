#include "leeway/core/confidence.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>

#include "leeway/core/error.hpp"
#include "leeway/core/kinematics.hpp"
#include "parallel.hpp"
#include "random.hpp"

namespace leeway {
namespace {

using detail::splitmix;
using detail::unit;

}  // namespace

std::pair<double, double> wilson_interval(long successes, long n) {
  if (n <= 0) return {0.0, 1.0};
  const double z = 1.959963984540054;
  const double p = static_cast<double>(successes) / static_cast<double>(n);
  const double nn = static_cast<double>(n);
  const double denom = 1 + z * z / nn;
  const double centre = (p + z * z / (2 * nn)) / denom;
  const double half = z * std::sqrt(p * (1 - p) / nn + z * z / (4 * nn * nn)) / denom;
  // At p = 0 or 1 the interval's end is exactly 0 or 1; rounding would put it a hair inside.
  const double low = successes == 0 ? 0.0 : std::max(0.0, centre - half);
  const double high = successes == n ? 1.0 : std::min(1.0, centre + half);
  return {low, high};
}

PathTiming time_path(const Scene& scene, const std::vector<WaypointBounds>& bounds) {
  PathTiming t;
  t.timed = bounds.size() >= 2;
  for (const auto& j : scene.joints()) t.timed = t.timed && j.max_speed > 0;
  t.segment_start.push_back(0.0);
  for (size_t i = 1; i < bounds.size(); ++i) {
    // Untimed (a joint without a speed): every segment lasts 1, the path parameter's own step.
    double d = t.timed ? 0.0 : 1.0;
    for (int j = 0; t.timed && j < scene.dof(); ++j)
      d = std::max(d, std::abs(bounds[i].q[j] - bounds[i - 1].q[j]) /
                          scene.joints()[static_cast<size_t>(j)].max_speed);
    t.segment.push_back(d);
    t.total += d;
    t.segment_start.push_back(t.total);
  }
  return t;
}

CfResult confidence_factor(const Scene& scene, const std::vector<WaypointBounds>& bounds,
                           const CfParams& params, int threads) {
  if (bounds.empty()) throw InputError("CF needs at least one bounded waypoint");
  require_joint_counts(scene, bounds);
  for (size_t i = 0; i < bounds.size(); ++i) {
    const auto& b = bounds[i];
    if (!b.lower.allFinite() || !b.upper.allFinite() || (b.lower.array() > b.upper.array()).any())
      throw InputError("bounds of waypoint " + std::to_string(i) + " are not finite or have lower > upper");
  }
  return confidence_factor(scene, BoundsTrajectory(scene, bounds), params, threads);
}

CfResult confidence_factor(const Scene& scene, const BoundsTrajectory& path, const CfParams& params,
                           int threads) {
  if (params.windows < 1) throw InputError("CF windows " + std::to_string(params.windows) + " must be >= 1");
  if (params.samples < 1) throw InputError("CF samples " + std::to_string(params.samples) + " must be >= 1");
  if (path.dof() != scene.dof())
    throw InputError("bounds of " + std::to_string(path.dof()) + " joints for the robot of " +
                     std::to_string(scene.dof()) + " in " + scene.source());
  const std::vector<WaypointBounds>& bounds = path.waypoints();
  std::vector<long> free_count(static_cast<size_t>(params.windows), 0);
  std::vector<long> obstacle_count(static_cast<size_t>(params.windows), 0);
  std::vector<long> self_count(static_cast<size_t>(params.windows), 0);
  std::vector<long> any_count(static_cast<size_t>(params.windows), 0);
  detail::parallel_for(params.windows, threads, [&] {
    // One RobotState (one mjData) per thread.
    auto state = std::make_shared<RobotState>(scene);
    return [&, state](int w) {
      std::mt19937_64 rng(splitmix(params.seed ^ splitmix(static_cast<std::uint64_t>(w))));
      Eigen::VectorXd q(scene.dof());
      long ok = 0, obstacle = 0, self = 0, any = 0;
      for (int k = 0; k < params.samples; ++k) {
        // A moment in window w (as a share of the path's duration), then its segment (the last
        // one starting at or before it: a segment of zero duration is never drawn) and the
        // position in it.
        const auto [seg, t] = path.locate_share((w + unit(rng)) / params.windows);
        const WaypointBounds& a = bounds[static_cast<size_t>(seg)];
        const WaypointBounds& b = bounds[std::min(bounds.size() - 1, static_cast<size_t>(seg) + 1)];
        detail::draw_in_segment(a.lower, a.upper, b.lower, b.upper, t, rng, q);
        const bool hit_obstacle = state->obstacle_contact(q);
        const bool hit_self = state->self_contact() >= 0;
        obstacle += hit_obstacle;
        self += hit_self;
        any += hit_obstacle || hit_self;
        ok += hit_obstacle || (params.self && hit_self) ? 0 : 1;
      }
      free_count[static_cast<size_t>(w)] = ok;
      obstacle_count[static_cast<size_t>(w)] = obstacle;
      self_count[static_cast<size_t>(w)] = self;
      any_count[static_cast<size_t>(w)] = any;
    };
  });

  CfResult r;
  r.duration = path.duration();
  r.timed = path.timed();
  long total_free = 0;
  r.worst_window_cf = 2;
  for (int w = 0; w < params.windows; ++w) {
    const double share = static_cast<double>(free_count[static_cast<size_t>(w)]) / params.samples;
    r.window_cf.push_back(share);
    total_free += free_count[static_cast<size_t>(w)];
    r.obstacle_collisions += obstacle_count[static_cast<size_t>(w)];
    r.self_collisions += self_count[static_cast<size_t>(w)];
    r.any_collisions += any_count[static_cast<size_t>(w)];
    if (share < r.worst_window_cf) {
      r.worst_window_cf = share;
      r.worst_window = w;
    }
  }
  r.samples = static_cast<long>(params.windows) * params.samples;
  r.collisions = r.samples - total_free;
  r.cf = static_cast<double>(total_free) / static_cast<double>(r.samples);
  std::tie(r.ci_low, r.ci_high) = wilson_interval(total_free, r.samples);
  return r;
}

}  // namespace leeway
