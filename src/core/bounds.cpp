#include "leeway/core/bounds.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <memory>
#include <string>

#include "leeway/core/error.hpp"
#include "leeway/core/scene.hpp"
#include "parallel.hpp"

namespace leeway {

namespace {

// Algorithm 2 in either direction (the limit above or below q[j]): A = the farthest value known
// collision-free, C = the nearest known colliding one, B = the probe. The loop runs while the probe
// is more than delta from A, as the thesis's listing has it (lines 10-20).
double bisect_towards(const CollisionFn& collides, Eigen::VectorXd q, int j, double limit, double delta,
                      long& checks) {
  double a = q[j];
  double b = limit;
  double c = b;
  q[j] = b;
  ++checks;
  if (!collides(q)) return b;
  b = (a + c) / 2;
  q[j] = b;
  double range = std::abs(b - a);
  while (range > delta) {
    ++checks;
    if (collides(q)) {
      c = b;
    } else {
      a = b;
    }
    b = (a + c) / 2;
    q[j] = b;
    range = std::abs(b - a);
  }
  return a;
}

// The preconditions of bound_upper (upper = true) and bound_lower.
void check_direction(const Eigen::VectorXd& q, int j, double limit, bool upper) {
  if (j < 0 || j >= q.size())
    throw InputError("joint index " + std::to_string(j) + " is outside a configuration of " +
                     std::to_string(q.size()) + " joints");
  if (upper ? !(limit >= q[j]) : !(limit <= q[j]))
    throw InputError(std::string(upper ? "upper" : "lower") + " limit " + format_number(limit) +
                     " of joint " + std::to_string(j) + " is " + (upper ? "below" : "above") + " its value " +
                     format_number(q[j]));
}

}  // namespace

WaypointBounds::WaypointBounds(Eigen::VectorXd q_in, Eigen::VectorXd lower_in, Eigen::VectorXd upper_in)
    : q(std::move(q_in)), lower(std::move(lower_in)), upper(std::move(upper_in)) {
  if (lower.size() != q.size() || upper.size() != q.size())
    throw InputError("waypoint bounds: q has " + std::to_string(q.size()) + " values, lower " +
                     std::to_string(lower.size()) + ", upper " + std::to_string(upper.size()));
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    const std::string joint = "waypoint bounds: joint " + std::to_string(i);
    if (!std::isfinite(q[i]) || !std::isfinite(lower[i]) || !std::isfinite(upper[i]))
      throw InputError(joint + ": a value is not finite (q " + format_number(q[i]) + ", bounds [" +
                       format_number(lower[i]) + ", " + format_number(upper[i]) + "])");
    if (!(lower[i] <= q[i] && q[i] <= upper[i]))
      throw InputError(joint + ": nominal " + format_number(q[i]) + " is not within [" +
                       format_number(lower[i]) + ", " + format_number(upper[i]) + "]");
  }
  collapsed.assign(static_cast<size_t>(q.size()), false);
  guide_lower = lower;
  guide_upper = upper;
}

std::pair<double, double> WaypointBounds::shrunk_by(Eigen::Index i) const {
  if (guide_lower.size() != lower.size() || guide_upper.size() != upper.size()) return {0.0, 0.0};
  return {lower[i] - guide_lower[i], guide_upper[i] - upper[i]};
}

bool WaypointBounds::contains(const Eigen::VectorXd& c) const {
  if (c.size() != lower.size() || c.size() != upper.size())
    throw InputError("configuration of " + std::to_string(c.size()) + " values against waypoint bounds of " +
                     std::to_string(lower.size()) + " joints");
  return (lower.array() <= c.array()).all() && (c.array() <= upper.array()).all();
}

double bound_upper(const CollisionFn& collides, Eigen::VectorXd q, int j, double limit, double delta,
                   long& checks) {
  check_direction(q, j, limit, true);
  return bisect_towards(collides, std::move(q), j, limit, delta, checks);
}

double bound_lower(const CollisionFn& collides, Eigen::VectorXd q, int j, double limit, double delta,
                   long& checks) {
  check_direction(q, j, limit, false);
  return bisect_towards(collides, std::move(q), j, limit, delta, checks);
}

void require_joint_counts(const Scene& scene, const std::vector<WaypointBounds>& bounds) {
  for (size_t k = 0; k < bounds.size(); ++k) {
    const auto& w = bounds[k];
    if (w.q.size() != scene.dof() || w.lower.size() != scene.dof() || w.upper.size() != scene.dof())
      throw InputError("bounds of waypoint " + std::to_string(k) + " have the wrong number of joints for " +
                       scene.source());
  }
}

std::vector<BoundKind> bound_kinds(const Scene& scene, const BoundsParams& params) {
  const auto& joints = scene.joints();
  std::vector<BoundKind> kinds;
  for (const auto& j : joints) kinds.push_back(j.prismatic ? BoundKind::kLinear : BoundKind::kFixed);
  if (params.bisect.empty()) {
    // The thesis's rule (section 3.3.1): the first three hinge joints, the arm without its wrist.
    int hinges = 0;
    for (size_t i = 0; i < joints.size(); ++i)
      if (!joints[i].prismatic && hinges++ < 3) kinds[i] = BoundKind::kBisected;
    return kinds;
  }
  for (const std::string& name : params.bisect) {
    const auto it =
        std::find_if(joints.begin(), joints.end(), [&name](const RobotJoint& j) { return j.name == name; });
    if (it == joints.end()) {
      std::string known;
      for (const auto& j : joints) known += (known.empty() ? "" : ", ") + j.name;
      throw InputError(scene.source() + ": parameter 'bounds.bisect' names joint '" + name +
                       "', which the robot does not have (joints: " + known + ")");
    }
    if (it->prismatic)
      throw InputError(scene.source() + ": parameter 'bounds.bisect' names slide joint '" + name +
                       "': only hinge joints are bisected (a slide joint's half-width is "
                       "'bounds.linear_axis_tolerance' or 'bounds.half_width')");
    kinds[static_cast<size_t>(it - joints.begin())] = BoundKind::kBisected;
  }
  return kinds;
}

double fixed_half_width(const Scene& scene, int index, const BoundsParams& params) {
  const RobotJoint& joint = scene.joints()[static_cast<size_t>(index)];
  const auto named = params.half_width.find(joint.name);
  if (named != params.half_width.end()) return named->second;
  return joint.prismatic ? params.linear_axis_tolerance * (joint.upper - joint.lower)
                         : params.wrist_half_width;
}

namespace {

// Runs `count` independent Algorithm-2 runs: run(k, collides) for k in [0, count), in any order and
// on any thread; each run writes only its own result.
using RunAll = std::function<void(int count, const std::function<void(int, const CollisionFn&)>& run)>;

WaypointBounds bound_waypoint_runs(const Scene& scene, const CollisionFn& collides, const RunAll& run_all,
                                   const Eigen::VectorXd& q, const BoundsParams& params) {
  scene.validate_configuration(q, "waypoint");
  const int n = scene.dof();
  const Eigen::VectorXd lo = scene.lower_limits(), hi = scene.upper_limits();
  for (int i = 0; i < n; ++i)
    if (q[i] < lo[i] || q[i] > hi[i])
      throw InputError("waypoint joint '" + scene.joints()[static_cast<size_t>(i)].name +
                       "' = " + format_number(q[i]) + " is outside its limits");
  WaypointBounds w;
  w.q = q;
  w.lower = q;
  w.upper = q;
  w.collapsed.assign(static_cast<size_t>(n), false);
  const auto kinds = bound_kinds(scene, params);
  std::vector<int> bisected;  // in model order, base to tip
  for (int i = 0; i < n; ++i) {
    if (kinds[static_cast<size_t>(i)] == BoundKind::kBisected) {
      bisected.push_back(i);
    } else {
      // The thesis leaves the wrist arbitrary (section 3.3.1) and gives the linear axis a fixed
      // tolerance (section 4.2.3); both are fixed here, clamped to the limits.
      const double half = fixed_half_width(scene, i, params);
      w.lower[i] = std::max(lo[i], q[i] - half);
      w.upper[i] = std::min(hi[i], q[i] + half);
    }
  }
  ++w.checks;
  w.nominal_in_volume = collides(q);

  // Algorithm 3: the first bisected joint at nominal; the second with the first at each of its
  // bounds; each later one with every combination of the earlier ones' bounds (the thesis's j1, j2,
  // j3). The most restrictive result is kept (highest lower, lowest upper). The runs of one joint
  // (2, then 4, 8, ...) are independent: run_all may spread them over threads; their results are
  // combined in a fixed order, so the bounds do not depend on how.
  std::vector<Eigen::VectorXd> bases = {q};
  for (int j : bisected) {
    const int runs = 2 * static_cast<int>(bases.size());
    std::vector<double> value(static_cast<size_t>(runs));
    std::vector<long> checks(static_cast<size_t>(runs), 0);
    run_all(runs, [&](int k, const CollisionFn& c) {
      const Eigen::VectorXd& base = bases[static_cast<size_t>(k / 2)];
      const size_t at = static_cast<size_t>(k);
      value[at] = k % 2 == 0 ? bound_lower(c, base, j, lo[j], params.resolution, checks[at])
                             : bound_upper(c, base, j, hi[j], params.resolution, checks[at]);
    });
    double lower = lo[j], upper = hi[j];
    for (int k = 0; k < runs; ++k) {
      const size_t at = static_cast<size_t>(k);
      if (k % 2 == 0)
        lower = std::max(lower, value[at]);
      else
        upper = std::min(upper, value[at]);
      w.checks += checks[at];
    }
    // Collapse guard (section 3.3): an interval shrunk to the nominal value gets a small one.
    if (upper - lower < params.resolution) {
      lower = std::max(lo[j], q[j] - params.min_half_width);
      upper = std::min(hi[j], q[j] + params.min_half_width);
      w.collapsed[static_cast<size_t>(j)] = true;
    }
    w.lower[j] = lower;
    w.upper[j] = upper;
    std::vector<Eigen::VectorXd> next;
    for (const Eigen::VectorXd& base : bases)
      for (double v : {lower, upper}) {
        Eigen::VectorXd b = base;
        b[j] = v;
        next.push_back(b);
      }
    bases = std::move(next);
  }
  w.guide_lower = w.lower;
  w.guide_upper = w.upper;
  return w;
}

}  // namespace

WaypointBounds bound_waypoint(const Scene& scene, const CollisionFn& collides, const Eigen::VectorXd& q,
                              const BoundsParams& params) {
  const RunAll in_order = [&collides](int count, const std::function<void(int, const CollisionFn&)>& run) {
    for (int k = 0; k < count; ++k) run(k, collides);
  };
  return bound_waypoint_runs(scene, collides, in_order, q, params);
}

std::vector<WaypointBounds> bound_path(const VolumeModel& world, const std::vector<Eigen::VectorXd>& path,
                                       const BoundsParams& params, int threads) {
  const Scene& scene = world.scene();
  std::vector<WaypointBounds> out(path.size());
  const int waypoints = static_cast<int>(path.size());
  threads = std::max(1, threads);
  // One VolumeChecker (one mjData) per thread, made once.
  std::vector<std::unique_ptr<VolumeChecker>> checkers;
  for (int t = 0; t < threads; ++t) checkers.push_back(std::make_unique<VolumeChecker>(world));
  // A probe collides when the robot touches the volume, or (bounds.self_collision) itself.
  auto collides_with = [&params](VolumeChecker& c) {
    return CollisionFn([&c, self = params.self_collision](const Eigen::VectorXd& q) {
      return c.in_collision(q) || (self && c.touches_itself());
    });
  };
  if (waypoints >= threads) {
    // Enough waypoints for every thread: one waypoint per task, its runs in order.
    std::atomic<int> slot{0};
    detail::parallel_for(waypoints, threads, [&] {
      VolumeChecker& checker = *checkers[static_cast<size_t>(slot++)];
      return [&](int i) {
        out[static_cast<size_t>(i)] =
            bound_waypoint(scene, collides_with(checker), path[static_cast<size_t>(i)], params);
      };
    });
    return out;
  }
  // Fewer waypoints than threads (the thesis's paths have two): waypoint after waypoint, the runs of
  // each joint level spread over the threads.
  const RunAll spread = [&](int count, const std::function<void(int, const CollisionFn&)>& run) {
    std::atomic<int> slot{0};
    detail::parallel_for(count, threads, [&] {
      const CollisionFn c = collides_with(*checkers[static_cast<size_t>(slot++)]);
      return [&run, c](int k) { run(k, c); };
    });
  };
  for (int i = 0; i < waypoints; ++i)
    out[static_cast<size_t>(i)] =
        bound_waypoint_runs(scene, collides_with(*checkers[0]), spread, path[static_cast<size_t>(i)], params);
  return out;
}

}  // namespace leeway
