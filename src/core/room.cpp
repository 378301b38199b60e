#include "leeway/core/room.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <random>

#include "leeway/core/box.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/shape.hpp"
#include "parallel.hpp"
#include "random.hpp"

namespace leeway {
namespace {

// The largest step of the free-range sweep where conservative advancement gives none [rad for
// hinges, m for slides]: beside a plane obstacle (which has no box to measure) or a self pair whose
// boxes overlap (their geoms may still be apart), the sweep samples at this step.
constexpr double kMaxHingeStep = 0.02;
constexpr double kMaxSlideStep = 0.005;
// Beside a self pair whose boxes are apart, a step is at least this share of that step: robot parts
// that pass each other closely without touching (the links of a long chain) would make the sweep
// crawl; such a pair is sampled eight times as densely as where boxes overlap.
constexpr double kSelfFloor = 1.0 / 8;
// The corners of every box are enumerated up to this many joints (2^10 = 1024 configurations).
constexpr int kMaxCornerJoints = 10;

// True when body `body` moves with `joint_body` (it is that body or a descendant of it).
bool moves_with(const mjModel& m, int body, int joint_body) {
  for (int b = body; b > 0; b = m.body_parentid[b])
    if (b == joint_body) return true;
  return false;
}

// A geom joint i moves, and its lever: the largest distance of a point of its box from the joint's
// axis (a hinge moves such a point by at most that times the angle, and the distance does not change
// as it turns); 1 for a slide, which moves every point by the step itself.
struct Moved {
  int geom = -1;
  double lever = 1.0;
  bool link = false;  // a link geom: checked against the obstacles
  Shape shape;        // at the sweep's current configuration (shape.box holds it)
  bool mesh = false;  // a mesh: its hull's extent, computed once
  HullExtent hull;
};

// A geom the joint does not move (an obstacle, or the other geom of a self pair): its shape stays.
struct Fixed {
  Shape shape;
  double margin = 0.0;
};

// Joint i's sweep at configuration q: the geoms it moves, the obstacles with a box, and the self
// pairs it moves one geom of (the index of that geom in `moved`, and the other one).
struct Sweep {
  std::vector<Moved> moved;
  std::vector<Fixed> obstacles;
  std::vector<std::pair<size_t, Fixed>> self;
  bool planes = false;  // an obstacle is a plane: no box bounds the step toward it
};

Sweep sweep_of(const Scene& scene, const mjData& d, int i) {
  const mjModel& m = scene.model();
  const RobotJoint& joint = scene.joints()[static_cast<size_t>(i)];
  const int joint_body = m.jnt_bodyid[joint.id];
  const Eigen::Vector3d anchor = vec3(d.xanchor + 3 * joint.id);
  const Eigen::Vector3d axis = vec3(d.xaxis + 3 * joint.id).normalized();
  Sweep s;
  std::vector<int> index(static_cast<size_t>(m.ngeom), -1);
  auto moved = [&](int g) {
    if (index[static_cast<size_t>(g)] >= 0) return static_cast<size_t>(index[static_cast<size_t>(g)]);
    Moved out{g, 1.0, false, geom_shape(m, d, g), m.geom_type[g] == mjGEOM_MESH, HullExtent{}};
    if (out.mesh) out.hull = hull_extent(m, g);
    if (!joint.prismatic) {
      out.lever = 1e-9;
      for (const Eigen::Vector3d& corner : box_corners(out.shape.box)) {
        const Eigen::Vector3d r = corner - anchor;
        out.lever = std::max(out.lever, (r - r.dot(axis) * axis).norm());
      }
    }
    index[static_cast<size_t>(g)] = static_cast<int>(s.moved.size());
    s.moved.push_back(out);
    return s.moved.size() - 1;
  };
  for (int g : scene.link_geoms())
    if (moves_with(m, m.geom_bodyid[g], joint_body)) s.moved[moved(g)].link = true;
  for (const RobotPair& p : scene.self_pairs()) {
    const bool first = moves_with(m, m.geom_bodyid[p.geom1], joint_body);
    if (first == moves_with(m, m.geom_bodyid[p.geom2], joint_body)) continue;
    const int other = first ? p.geom2 : p.geom1;
    s.self.emplace_back(moved(first ? p.geom1 : p.geom2),
                        Fixed{geom_shape(m, d, other), m.geom_margin[other]});
  }
  for (int o : scene.obstacle_geoms()) {
    if (has_bounding_box(m, o))
      s.obstacles.push_back(Fixed{geom_shape(m, d, o), m.geom_margin[o]});
    else
      s.planes = true;
  }
  return s;
}

// A lower bound of how far a moved geom is from touching a fixed one: their shapes' distance (as
// MuJoCo collides them: shape.hpp) less the contact margin. `limit`: a bound the caller needs only
// when it is smaller (the shapes' bounding spheres answer the rest without the exact distance).
double gap(const Moved& g, const Fixed& f, double margin, double limit) {
  const double spheres =
      (g.shape.box.center - f.shape.box.center).norm() - g.shape.radius - f.shape.radius - margin;
  if (spheres >= limit) return spheres;
  return shape_distance(g.shape, f.shape) - margin;
}

// How far the joint may move [rad or m] before a geom of `sweep` can touch an obstacle or its
// self-pair partner: per pair, its gap (a lower bound of the true clearance) over the moved geom's
// lever. A self pair whose boxes overlap, or a plane obstacle, caps it at `sampled`; a self pair
// whose boxes are apart allows at least kSelfFloor of it. The moved geoms' boxes are updated to the
// configuration of `d` first.
double sweep_step(const mjModel& m, const mjData& d, Sweep& sweep, double sampled) {
  for (Moved& g : sweep.moved) g.shape = geom_shape(m, d, g.geom, g.mesh ? &g.hull : nullptr);
  double step = sweep.planes ? sampled : INFINITY;
  for (const Fixed& o : sweep.obstacles)
    for (const Moved& g : sweep.moved) {
      if (!g.link) continue;
      const double margin = std::max(m.geom_margin[g.geom], o.margin);
      step = std::min(step, gap(g, o, margin, step * g.lever) / g.lever);
    }
  for (const auto& [k, other] : sweep.self) {
    const Moved& g = sweep.moved[k];
    const double margin = std::max(m.geom_margin[g.geom], other.margin);
    // Below the floor a pair with its boxes apart no longer lowers the step: its exact gap matters
    // only down to there.
    const double apart = gap(g, other, margin, std::max(step, kSelfFloor * sampled) * g.lever);
    step = std::min(step, apart > 0 ? std::max(apart / g.lever, kSelfFloor * sampled) : sampled);
  }
  return step;
}

// How far joint i moves from q[i] in direction `sign` before the robot collides, within `limit`.
double sweep_side(RobotState& state, Sweep& sweep, Eigen::VectorXd q, int i, double sign, double limit,
                  double tolerance) {
  const Scene& scene = state.scene();
  const double sampled = scene.joints()[static_cast<size_t>(i)].prismatic ? kMaxSlideStep : kMaxHingeStep;
  const double start = q[i];
  double free = start;
  while (sign * (limit - free) > 0) {
    state.set(q);
    const double advance = std::max(sweep_step(scene.model(), state.data(), sweep, sampled), tolerance);
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
    Sweep sweep = sweep_of(scene, state.data(), i);
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
