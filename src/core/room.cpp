#include "leeway/core/room.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <random>

#include "leeway/core/box.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/kinematics.hpp"
#include "parallel.hpp"
#include "random.hpp"

namespace leeway {
namespace {

// The largest step of the free-range sweep where conservative advancement does not bound it [rad
// for hinges, m for slides]: beside a plane obstacle (which has no box to measure) or a self pair
// whose boxes overlap (their geoms may still be apart), the sweep samples at this step.
constexpr double kMaxHingeStep = 0.02;
constexpr double kMaxSlideStep = 0.005;
// The corners of every box are enumerated up to this many joints (2^10 = 1024 configurations).
constexpr int kMaxCornerJoints = 10;

// True when body `body` moves with `joint_body` (it is that body or a descendant of it).
bool moves_with(const mjModel& m, int body, int joint_body) {
  for (int b = body; b > 0; b = m.body_parentid[b])
    if (b == joint_body) return true;
  return false;
}

// Joint i's sweep at configuration q: the link geoms it moves, the self pairs it moves one geom of
// (that geom first), and the largest distance of a point of the moved geoms' boxes from its axis (a
// hinge moves such a point by at most that lever times the angle, and the distance from its own
// axis does not change as it turns).
struct Sweep {
  std::vector<int> geoms;
  std::vector<std::pair<int, int>> self;
  bool planes = false;  // an obstacle is a plane: no box bounds the step toward it
  double lever = 0.0;
};

Sweep sweep_of(const Scene& scene, const mjData& d, int i) {
  const mjModel& m = scene.model();
  const RobotJoint& joint = scene.joints()[static_cast<size_t>(i)];
  const int joint_body = m.jnt_bodyid[joint.id];
  const Eigen::Vector3d anchor = vec3(d.xanchor + 3 * joint.id);
  const Eigen::Vector3d axis = vec3(d.xaxis + 3 * joint.id).normalized();
  Sweep s;
  auto reach = [&](int g) {
    const Box b = geom_box(m, d, g);
    for (int c = 0; c < 8; ++c) {
      Eigen::Vector3d corner = b.half_size;
      for (int k = 0; k < 3; ++k)
        if (c & (1 << k)) corner[k] = -corner[k];
      const Eigen::Vector3d r = b.center + b.rotation * corner - anchor;
      s.lever = std::max(s.lever, (r - r.dot(axis) * axis).norm());
    }
  };
  for (int g : scene.link_geoms()) {
    if (!moves_with(m, m.geom_bodyid[g], joint_body)) continue;
    s.geoms.push_back(g);
    reach(g);
  }
  for (const RobotPair& p : scene.self_pairs()) {
    const bool first = moves_with(m, m.geom_bodyid[p.geom1], joint_body);
    if (first == moves_with(m, m.geom_bodyid[p.geom2], joint_body)) continue;
    s.self.emplace_back(first ? p.geom1 : p.geom2, first ? p.geom2 : p.geom1);
    reach(s.self.back().first);
  }
  for (int o : scene.obstacle_geoms()) s.planes = s.planes || !has_bounding_box(m, o);
  return s;
}

// The box distance of two geoms less their contact margin (a lower bound of how far they are from
// touching).
double gap(const mjModel& m, const mjData& d, int g1, int g2) {
  return box_distance(geom_box(m, d, g1), geom_box(m, d, g2)) -
         std::max(m.geom_margin[g1], m.geom_margin[g2]);
}

// How far the geoms of `sweep` may move before one can touch an obstacle or its self-pair partner:
// the smallest gap, a lower bound of the true clearance. A self pair whose boxes overlap, or a plane
// obstacle, caps it at `sampled` (the sweep then samples, as it must for them).
double sweep_clearance(const Scene& scene, const mjData& d, const Sweep& sweep, double sampled) {
  const mjModel& m = scene.model();
  double best = sweep.planes ? sampled : INFINITY;
  for (int o : scene.obstacle_geoms()) {
    if (!has_bounding_box(m, o)) continue;
    for (int g : sweep.geoms) best = std::min(best, gap(m, d, g, o));
  }
  for (const auto& [moved, other] : sweep.self) {
    const double g = gap(m, d, moved, other);
    best = std::min(best, g > 0 ? g : sampled);
  }
  return best;
}

// How far joint i moves from q[i] in direction `sign` before the robot collides, within `limit`.
double sweep_side(RobotState& state, const Sweep& sweep, Eigen::VectorXd q, int i, double sign, double limit,
                  double tolerance) {
  const Scene& scene = state.scene();
  const bool slide = scene.joints()[static_cast<size_t>(i)].prismatic;
  // A slide moves every point of its geoms by the step itself (lever 1).
  const double lever = slide ? 1.0 : std::max(sweep.lever, 1e-9);
  const double sampled = (slide ? kMaxSlideStep : kMaxHingeStep) * lever;
  const double start = q[i];
  double free = start;
  while (sign * (limit - free) > 0) {
    state.set(q);
    const double advance = std::max(sweep_clearance(scene, state.data(), sweep, sampled) / lever, tolerance);
    const double next = sign > 0 ? std::min(limit, free + advance) : std::max(limit, free - advance);
    q[i] = next;
    if (!state.in_collision(q)) {
      free = next;
      continue;
    }
    double bad = next;
    while (std::abs(bad - free) > tolerance) {
      q[i] = (free + bad) / 2;
      (state.in_collision(q) ? bad : free) = q[i];
    }
    break;
  }
  return free;
}

}  // namespace

std::vector<FreeRange> one_joint_free_ranges(RobotState& state, const Eigen::VectorXd& q, double tolerance) {
  const Scene& scene = state.scene();
  scene.validate_configuration(q, "configuration");
  if (!(tolerance > 0) || !std::isfinite(tolerance))
    throw InputError("free range tolerance must be positive and finite, got " + format_number(tolerance));
  const int n = scene.dof();
  std::vector<FreeRange> out(static_cast<size_t>(n), FreeRange{});
  const bool blocked = state.in_collision(q);
  for (int i = 0; i < n; ++i) {
    FreeRange& r = out[static_cast<size_t>(i)];
    r.lower = r.upper = q[i];
    if (blocked) continue;
    state.set(q);
    const Sweep sweep = sweep_of(scene, state.data(), i);
    const RobotJoint& joint = scene.joints()[static_cast<size_t>(i)];
    r.lower = sweep_side(state, sweep, q, i, -1.0, joint.lower, tolerance);
    r.upper = sweep_side(state, sweep, q, i, +1.0, joint.upper, tolerance);
  }
  return out;
}

namespace {

// The tool's room at one waypoint: the box's corners and `samples` seeded random configurations.
void tool_room(RobotState& state, const WaypointBounds& w, const RoomOptions& options, std::uint64_t stream,
               WaypointRoom& room) {
  const Pose nominal = state.fk(w.q);
  const int n = static_cast<int>(w.q.size());
  auto visit = [&](const Eigen::VectorXd& c) {
    const Pose p = state.fk(c);
    room.tool_translation = std::max(room.tool_translation, (p.position - nominal.position).norm());
    const Eigen::Matrix3d rel = nominal.rotation.transpose() * p.rotation;
    const double cos_angle = std::clamp((rel.trace() - 1) / 2, -1.0, 1.0);
    room.tool_rotation = std::max(room.tool_rotation, std::acos(cos_angle));
  };
  std::mt19937_64 rng(detail::splitmix(options.seed ^ detail::splitmix(stream)));
  Eigen::VectorXd c(n);
  const long corners = n <= kMaxCornerJoints ? (1L << n) : (1L << kMaxCornerJoints);
  for (long k = 0; k < corners; ++k) {
    for (int i = 0; i < n; ++i) {
      const bool up = n <= kMaxCornerJoints ? ((k >> i) & 1) != 0 : detail::unit(rng) < 0.5;
      c[i] = up ? w.upper[i] : w.lower[i];
    }
    visit(c);
  }
  for (int s = 0; s < options.tool_samples; ++s) {
    detail::draw_in_segment(w.lower, w.upper, w.lower, w.upper, 0.0, rng, c);
    visit(c);
  }
}

}  // namespace

RoomReport measure_room(const Scene& scene, const std::vector<WaypointBounds>& bounds,
                        const RoomOptions& options, int threads) {
  const auto t0 = std::chrono::steady_clock::now();
  require_joint_counts(scene, bounds);
  if (options.tool_samples < 0 || options.max_waypoints < 0)
    throw InputError("room: tool samples and the waypoint count must not be negative, got " +
                     std::to_string(options.tool_samples) + " and " + std::to_string(options.max_waypoints));
  const int n = scene.dof();
  RoomReport report;
  const size_t count = bounds.size();
  const size_t measured = options.max_waypoints > 0 && count > static_cast<size_t>(options.max_waypoints)
                              ? static_cast<size_t>(std::max(2, options.max_waypoints))
                              : count;
  report.waypoints.resize(measured);
  for (size_t j = 0; j < measured; ++j)
    report.waypoints[j].waypoint =
        measured == count ? j : (j * (count - 1) + (measured - 1) / 2) / (measured - 1);
  detail::parallel_for(static_cast<int>(measured), threads, [&] {
    auto state = std::make_shared<RobotState>(scene);
    return [&, state](int j) {
      WaypointRoom& room = report.waypoints[static_cast<size_t>(j)];
      const size_t k = room.waypoint;
      const WaypointBounds& w = bounds[k];
      room.free = one_joint_free_ranges(*state, w.q, options.tolerance);
      room.share = Eigen::VectorXd::Constant(n, std::nan(""));
      for (int i = 0; i < n; ++i) {
        const FreeRange& f = room.free[static_cast<size_t>(i)];
        const double width = f.upper - f.lower;
        if (width > options.tolerance)
          room.share[i] = std::clamp((w.upper[i] - w.lower[i]) / width, 0.0, 1.0);
      }
      tool_room(*state, w, options, static_cast<std::uint64_t>(k), room);
    };
  });
  report.joint_share = Eigen::VectorXd::Constant(n, std::nan(""));
  double sum = 0;
  int defined = 0;
  for (int i = 0; i < n; ++i) {
    double joint_sum = 0;
    int waypoints = 0;
    for (const auto& room : report.waypoints)
      if (!std::isnan(room.share[i])) {
        joint_sum += room.share[i];
        ++waypoints;
      }
    if (waypoints == 0) continue;
    report.joint_share[i] = joint_sum / waypoints;
    sum += report.joint_share[i];
    ++defined;
  }
  report.mean_share = defined ? sum / defined : std::nan("");
  report.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

}  // namespace leeway
