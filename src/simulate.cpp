#include "leeway/simulate.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include "leeway/box.hpp"
#include "leeway/collision.hpp"
#include "leeway/error.hpp"
#include "random.hpp"

namespace leeway {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMaxForce = 1e4;   // [N]: a push file's limit
constexpr double kMaxTorque = 1e4;  // [N m]

void require_range(double value, double low, double high, const std::string& name, const std::string& unit,
                   bool open_low = false) {
  const bool ok = std::isfinite(value) && (open_low ? value > low : value >= low) && value <= high;
  if (!ok)
    throw InputError("simulate: " + name + " " + format_number(value) + " is outside " +
                     (open_low ? "(" : "[") + format_number(low) + ", " + format_number(high) + "]" +
                     (unit.empty() ? "" : " " + unit));
}

// Splits a line at commas and white space.
std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : line) {
    if (c == ',' || c == ' ' || c == '\t' || c == '\r') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

bool parse_double(const std::string& text, double& value) {
  std::istringstream in(text);
  in.imbue(std::locale::classic());
  in >> value;
  return in && in.peek() == std::char_traits<char>::eof();
}

// The point of geom g nearest to p (world frame), in MuJoCo's geom frame conventions: exact for
// boxes, spheres, capsules and cylinders; other types are taken as their bounding sphere.
Eigen::Vector3d nearest_point(const mjModel& m, const mjData& d, int g, const Eigen::Vector3d& p) {
  const Eigen::Map<const Eigen::Vector3d> x(d.geom_xpos + 3 * g);
  const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> r(d.geom_xmat + 9 * g);
  const Eigen::Vector3d local = r.transpose() * (p - x);
  const double* size = m.geom_size + 3 * g;
  Eigen::Vector3d c = local;
  switch (m.geom_type[g]) {
    case mjGEOM_BOX:
      for (int i = 0; i < 3; ++i) c[i] = std::clamp(local[i], -size[i], size[i]);
      break;
    case mjGEOM_SPHERE:
      if (local.norm() > size[0]) c = local.normalized() * size[0];
      break;
    case mjGEOM_CAPSULE: {
      Eigen::Vector3d axis(0, 0, std::clamp(local.z(), -size[1], size[1]));
      const Eigen::Vector3d off = local - axis;
      c = off.norm() > size[0] ? axis + off.normalized() * size[0] : local;
      break;
    }
    case mjGEOM_CYLINDER: {
      Eigen::Vector2d radial(local.x(), local.y());
      if (radial.norm() > size[0]) radial = radial.normalized() * size[0];
      c = Eigen::Vector3d(radial.x(), radial.y(), std::clamp(local.z(), -size[1], size[1]));
      break;
    }
    default: {
      const double rb = m.geom_rbound[g];
      if (local.norm() > rb) c = local.normalized() * rb;
      break;
    }
  }
  return x + r * c;
}

// The obstacle geoms a push-toward target names: a geom, or every obstacle geom of a body.
std::vector<int> target_geoms(const Scene& scene, const std::string& target) {
  const mjModel& m = scene.model();
  if (target == "nearest") return scene.obstacle_geoms();
  std::vector<int> out;
  const int g = mj_name2id(&m, mjOBJ_GEOM, target.c_str());
  if (g >= 0 && scene.role(g) == GeomRole::kObstacle) return {g};
  const int b = mj_name2id(&m, mjOBJ_BODY, target.c_str());
  if (b >= 0)
    for (int o : scene.obstacle_geoms())
      if (m.geom_bodyid[o] == b) out.push_back(o);
  if (out.empty()) {
    std::string names;
    int listed = 0;
    for (int o : scene.obstacle_geoms()) {
      const std::string name = object_name(m, mjOBJ_GEOM, o);
      if (name.empty() || listed >= 20) continue;
      names += (listed++ ? ", " : "") + name;
    }
    throw InputError(
        "simulate: --human push-toward '" + target +
        "' names no obstacle geom or body with obstacle geoms in " + scene.source() +
        (names.empty() ? "" : " (obstacle geoms: " + names + (listed >= 20 ? ", ..." : "") + ")") +
        "; 'nearest' pushes toward the nearest obstacle");
  }
  return out;
}

// The human: a wrench at the tool site for the current state.
class Human {
 public:
  Human(const Scene& scene, const HumanOptions& options, std::uint64_t seed, double period)
      : scene_(scene), options_(options), rng_(detail::splitmix(seed)), period_(period) {
    if (options.kind == HumanKind::kPushToward) targets_ = target_geoms(scene, options.target);
  }

  // The wrench (force, torque) at time t with the tool at `tool`.
  std::pair<Eigen::Vector3d, Eigen::Vector3d> wrench(double t, const mjData& d, const Eigen::Vector3d& tool) {
    const mjModel& m = scene_.model();
    switch (options_.kind) {
      case HumanKind::kNone:
        return {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
      case HumanKind::kRandom: {
        // White noise through two first-order low-passes at the bandwidth, exactly discretised;
        // the first stage's output has unit variance, the second scales to the amplitude.
        const double lambda = 2 * kPi * options_.bandwidth;
        const double decay = std::exp(-lambda * period_);
        const double noise = std::sqrt(1 - decay * decay);
        std::normal_distribution<double> normal;
        for (int i = 0; i < 3; ++i) {
          stage1_[i] = decay * stage1_[i] + noise * normal(rng_);
          stage2_[i] = decay * stage2_[i] + (1 - decay) * stage1_[i];
        }
        // Two equal first-order stages pass half the variance of the first one's output.
        return {options_.amplitude * std::sqrt(2.0) * stage2_, Eigen::Vector3d::Zero()};
      }
      case HumanKind::kPushToward: {
        double best = kInf;
        Eigen::Vector3d toward = Eigen::Vector3d::Zero();
        for (int g : targets_) {
          const Eigen::Vector3d c = nearest_point(m, d, g, tool);
          const double dist = (c - tool).norm();
          if (dist < best) {
            best = dist;
            toward = c - tool;
          }
        }
        if (toward.norm() < 1e-9) return {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
        // Ramp up over the first half second: a person does not strike.
        const double ramp = std::min(1.0, t / 0.5);
        return {options_.amplitude * ramp * toward.normalized(), Eigen::Vector3d::Zero()};
      }
      case HumanKind::kFile: {
        const auto& s = options_.samples;
        if (s.empty() || t < s.front().t || t > s.back().t)
          return {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
        auto hi =
            std::upper_bound(s.begin(), s.end(), t, [](double v, const WrenchSample& w) { return v < w.t; });
        if (hi == s.end()) return {s.back().force, s.back().torque};
        const auto lo = hi - 1;
        const double f = (t - lo->t) / (hi->t - lo->t);
        return {lo->force + f * (hi->force - lo->force), lo->torque + f * (hi->torque - lo->torque)};
      }
    }
    return {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  }

 private:
  const Scene& scene_;
  HumanOptions options_;
  std::mt19937_64 rng_;
  double period_;
  std::vector<int> targets_;
  Eigen::Vector3d stage1_ = Eigen::Vector3d::Zero(), stage2_ = Eigen::Vector3d::Zero();
};

}  // namespace

std::vector<WrenchSample> read_wrench_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot read the push file");
  std::vector<WrenchSample> out;
  std::string line;
  int number = 0;
  bool header_allowed = true;
  while (std::getline(in, line)) {
    ++number;
    const std::string where = path + " line " + std::to_string(number);
    const auto f = fields(line);
    if (f.empty() || f[0][0] == '#') continue;
    double first = 0;
    if (header_allowed && !parse_double(f[0], first)) {
      header_allowed = false;
      continue;
    }
    header_allowed = false;
    if (f.size() != 4 && f.size() != 7)
      throw InputError(where + ": " + std::to_string(f.size()) +
                       " values; a sample is t fx fy fz [tx ty tz] (s, N, N m)");
    double v[7] = {0, 0, 0, 0, 0, 0, 0};
    for (size_t i = 0; i < f.size(); ++i)
      if (!parse_double(f[i], v[i]) || !std::isfinite(v[i]))
        throw InputError(where + ": '" + f[i] + "' is not a finite number");
    WrenchSample w;
    w.t = v[0];
    w.force = Eigen::Vector3d(v[1], v[2], v[3]);
    w.torque = Eigen::Vector3d(v[4], v[5], v[6]);
    if (w.t < 0) throw InputError(where + ": time " + f[0] + " s is negative");
    if (!out.empty() && !(w.t > out.back().t))
      throw InputError(where + ": time " + f[0] + " s does not come after " + format_number(out.back().t) +
                       " s (times must increase)");
    if (w.force.norm() > kMaxForce)
      throw InputError(where + ": force " + format_number(w.force.norm()) + " N is over 10 kN");
    if (w.torque.norm() > kMaxTorque)
      throw InputError(where + ": torque " + format_number(w.torque.norm()) + " N m is over 10 kN m");
    out.push_back(w);
  }
  if (out.empty()) throw InputError(path + ": no samples (t fx fy fz [tx ty tz] per line)");
  return out;
}

void SimulateOptions::check() const {
  require_range(human.amplitude, 0, 2000, "human amplitude", "N");
  require_range(human.bandwidth, 0, 20, "human bandwidth", "Hz", true);
  require_range(speed, 0, 10, "speed", "(share of the nominal speed)", true);
  require_range(control_period, 1e-4, 0.1, "control period", "s");
  require_range(admittance_inertia, 1e-3, 1e4, "admittance inertia", "kg m^2");
  require_range(admittance_damping, 1e-3, 1e5, "admittance damping", "N m s/rad");
  require_range(speed_scale, 0, 100, "speed scale", "", true);
  require_range(default_speed, 0, 100, "default speed", "rad/s", true);
  require_range(max_accel, 0, 1e4, "max acceleration", "rad/s^2", true);
  require_range(hold_force, 0, 1e4, "hold force", "N", true);
  require_range(plan_margin, 0, 0.1, "plan margin", "rad");
  require_range(servo_bandwidth, 0, 1000, "servo bandwidth", "Hz", true);
  require_range(distance_range, 0, 10, "distance range", "m", true);
  require_range(end_hold, 0, 3600, "end hold", "s");
  require_range(max_time, 0, 36000, "max time", "s");
}

SimulationReport simulate(const Scene& scene, const BoundsTrajectory& bounds, const SimulateOptions& options,
                          const FrameCallback& on_frame) {
  options.check();
  const auto wall_start = std::chrono::steady_clock::now();
  const int n = scene.dof();
  if (bounds.dof() != n)
    throw InputError("simulate: the bounds have " + std::to_string(bounds.dof()) + " joints, the cell " +
                     std::to_string(n));

  // A copy of the model, so that the scene is not changed.
  ModelPtr model(mj_copyModel(nullptr, &scene.model()));
  mjModel& m = *model;
  m.opt.integrator = mjINT_EULER;  // mj_step1/mj_step2 need it
  const double dt = m.opt.timestep;
  const int substeps = static_cast<int>(std::lround(options.control_period / dt));
  if (substeps < 1 || std::abs(substeps * dt - options.control_period) > 1e-9 * options.control_period)
    throw InputError("simulate: the control period " + format_number(options.control_period) +
                     " s is not a multiple of the cell's timestep " + format_number(dt) + " s (" +
                     scene.source() + ", <option timestep>)");
  const double hc = options.control_period;

  DataPtr data = make_data(m);
  mjData& d = *data;
  DataPtr scratch = make_data(m);  // kinematics of nominal configurations

  std::vector<int> qadr(n), vadr(n);
  Eigen::VectorXd vmax(n);
  for (int j = 0; j < n; ++j) {
    const RobotJoint& joint = scene.joints()[j];
    qadr[j] = m.jnt_qposadr[joint.id];
    vadr[j] = m.jnt_dofadr[joint.id];
    vmax[j] = joint.max_speed > 0 ? options.speed_scale * joint.max_speed : options.default_speed;
  }
  const int site = scene.tool_site();
  const int tool_body = m.site_bodyid[site];

  std::vector<JointMpc> mpcs;
  for (int j = 0; j < n; ++j) {
    JointMpcOptions o = options.mpc;
    o.max_speed = vmax[j];
    o.max_accel = options.max_accel;
    mpcs.emplace_back(o);
  }

  Human human(scene, options.human, options.seed, hc);

  // Path progress: ds/dt at s under the nominal timing (a segment of zero duration is passed at once).
  const auto& times = bounds.times();
  const double s_end = bounds.s_end();
  const auto nominal_rate = [&](double s) {
    const int i = std::min(static_cast<int>(s), std::max(0, bounds.waypoint_count() - 2));
    const double duration = bounds.waypoint_count() > 1 ? times[i + 1] - times[i] : 0;
    return duration > 0 ? 1.0 / duration : 1e6;
  };
  // dq/ds of the segment at s (the last segment's at the end).
  const auto path_slope = [&](double s) -> Eigen::VectorXd {
    if (bounds.waypoint_count() < 2) return Eigen::VectorXd::Zero(n);
    const int i = std::min(static_cast<int>(s), bounds.waypoint_count() - 2);
    return bounds.waypoints()[static_cast<size_t>(i) + 1].q - bounds.waypoints()[static_cast<size_t>(i)].q;
  };
  const auto tool_at = [&](const Eigen::VectorXd& q) {
    scene.set_qpos(*scratch, q);
    mj_kinematics(&m, scratch.get());
    return Eigen::Vector3d(scratch->site_xpos[3 * site], scratch->site_xpos[3 * site + 1],
                           scratch->site_xpos[3 * site + 2]);
  };

  SimulationReport report;
  report.timestep = dt;
  report.nominal_duration = bounds.duration();
  report.waypoint_times.assign(bounds.waypoint_count(), std::numeric_limits<double>::quiet_NaN());
  report.waypoint_times[0] = 0;
  report.freedom_used = Eigen::VectorXd::Zero(n);
  report.max_deviation = Eigen::VectorXd::Zero(n);
  report.min_distance = options.distance_range;
  report.min_distance_capped = true;
  const double max_time =
      options.max_time > 0 ? options.max_time : 3 * bounds.duration() / options.speed + options.end_hold + 5;

  // The start: the first waypoint's nominal configuration, at rest.
  Eigen::VectorXd nom(n), lo(n), hi(n);
  bounds.at_s(0, nom, lo, hi);
  scene.set_qpos(d, nom);
  mj_forward(&m, &d);

  Eigen::VectorXd qc = nom, vc = Eigen::VectorXd::Zero(n), ac = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd dev = Eigen::VectorXd::Zero(n), dev_rate = Eigen::VectorXd::Zero(n);
  double s = 0, s_from = 0, s_to = 0;
  double reached_at = -1;
  double rate_prev = 0;  // ds/dt of the last control period
  Eigen::Vector3d force = Eigen::Vector3d::Zero(), torque = Eigen::Vector3d::Zero();
  double force_sq_sum = 0;
  long force_samples = 0;

  const double kp_omega = 2 * kPi * options.servo_bandwidth;
  const double kp = kp_omega * kp_omega, kd = 2 * kp_omega;
  std::vector<mjtNum> jacp(3 * m.nv), jacr(3 * m.nv), acc(m.nv), mass_acc(m.nv);
  Eigen::VectorXd human_gen(m.nv);
  const std::vector<RobotPair>& self_pairs = scene.self_pairs();
  // The boxes of the distance measurement: the cell's are fixed (taken once), the robot's are taken
  // at every step for the geoms that move or pair with one.
  std::vector<Box> boxes(static_cast<size_t>(m.ngeom));
  std::vector<Aabb> box_bounds(static_cast<size_t>(m.ngeom));
  std::vector<int> robot_geoms = scene.link_geoms();
  for (const RobotPair& p : self_pairs)
    for (int g : {p.geom1, p.geom2})
      if (std::find(robot_geoms.begin(), robot_geoms.end(), g) == robot_geoms.end()) robot_geoms.push_back(g);
  const auto take_box = [&](int g) {
    const Box b = geom_box(m, d, g);
    const Eigen::Vector3d extent = b.rotation.cwiseAbs() * b.half_size;
    boxes[static_cast<size_t>(g)] = b;
    box_bounds[static_cast<size_t>(g)] = {b.center - extent, b.center + extent};
  };
  mj_kinematics(&m, &d);
  for (int o : scene.obstacle_geoms())
    if (has_bounding_box(m, o)) take_box(o);
  // A lower bound of the distance between two geoms' boxes: the gap between their bounding boxes.
  const auto bound_gap = [&](int g1, int g2) {
    const Aabb& a = box_bounds[static_cast<size_t>(g1)];
    const Aabb& b = box_bounds[static_cast<size_t>(g2)];
    const Eigen::Vector3d gap = (a.lo - b.hi).cwiseMax(b.lo - a.hi).cwiseMax(0.0);
    return gap.norm();
  };

  // Stage ends of the MPC's horizon [s after now].
  const JointMpcOptions& mo = options.mpc;
  Eigen::VectorXd stage_end(mo.horizon);
  for (int k = 0; k < mo.horizon; ++k) stage_end[k] = (k ? stage_end[k - 1] + mo.period : mo.first_period);

  Eigen::VectorXd n_k(n), lo_k(n), hi_k(n);
  Eigen::VectorXd ref(mo.horizon), lower(mo.horizon), upper(mo.horizon);
  std::vector<Eigen::VectorXd> stage_lo(mo.horizon, Eigen::VectorXd(n)),
      stage_hi(mo.horizon, Eigen::VectorXd(n)), stage_nom(mo.horizon, Eigen::VectorXd(n));

  // The push's generalized force J^T w at the current state.
  const auto push_on_joints = [&] {
    mj_jacSite(&m, &d, jacp.data(), jacr.data(), site);
    for (int i = 0; i < m.nv; ++i) {
      double g = 0;
      for (int r = 0; r < 3; ++r) g += jacp[r * m.nv + i] * force[r] + jacr[r * m.nv + i] * torque[r];
      human_gen[i] = g;
    }
  };

  const long total_steps = static_cast<long>(std::ceil(max_time / dt));
  for (long step = 0; step < total_steps; ++step) {
    const double t = static_cast<double>(step) * dt;
    const int sub = static_cast<int>(step % substeps);
    mj_step1(&m, &d);  // kinematics, contacts, mass matrix and bias forces at the current state

    Eigen::VectorXd q(n), v(n);
    for (int j = 0; j < n; ++j) {
      q[j] = d.qpos[qadr[j]];
      v[j] = d.qvel[vadr[j]];
    }
    const Eigen::Vector3d tool(d.site_xpos[3 * site], d.site_xpos[3 * site + 1], d.site_xpos[3 * site + 2]);

    if (sub == 0) {
      // The controller's period starts: the push, the admittance, the progress and the plan.
      std::tie(force, torque) = human.wrench(t, d, tool);
      force_sq_sum += force.squaredNorm();
      ++force_samples;
      report.max_force = std::max(report.max_force, force.norm());
      push_on_joints();
      // Admittance per joint: M dd + D d = J^T w.
      for (int j = 0; j < n; ++j) {
        const double tau = human_gen[vadr[j]];
        dev_rate[j] += hc * (tau - options.admittance_damping * dev_rate[j]) / options.admittance_inertia;
        dev[j] += hc * dev_rate[j];
      }
      // Progress: the nominal rate scaled by the speed, slowed by a push against the direction of
      // travel, and no farther than the command can follow within this period.
      bounds.at_s(s, nom, lo, hi);
      const Eigen::Vector3d ahead = tool_at(bounds.at_s(std::min(s_end, s + 0.01)).nominal) - tool_at(nom);
      double slow = 1;
      if (ahead.norm() > 1e-9) {
        const double against = std::max(0.0, -force.dot(ahead.normalized()));
        slow = std::clamp(1 - against / options.hold_force, 0.0, 1.0);
      }
      // The rate is limited so that following the nominal path alone needs at most half of each
      // joint's speed and acceleration limits (the rest is the co-worker's), and ramps up and down.
      const Eigen::VectorXd slope = path_slope(s);
      double rate_max = options.speed * nominal_rate(s), accel_s = kInf;
      for (int j = 0; j < n; ++j)
        if (std::abs(slope[j]) > 1e-12) {
          rate_max = std::min(rate_max, 0.5 * vmax[j] / std::abs(slope[j]));
          accel_s = std::min(accel_s, 0.5 * options.max_accel / std::abs(slope[j]));
        }
      double rate = std::min({rate_max * slow, rate_prev + accel_s * hc});
      if (std::isfinite(accel_s)) rate = std::min(rate, std::sqrt(2 * accel_s * std::max(0.0, s_end - s)));
      rate = std::max(rate, 0.0);
      const double target = std::min(s_end, s + rate * hc);

      // The boxes and the reference over the horizon, the progress going on at the wished rate. The
      // first stage also stays in the box at the current s, so that progress can always wait for
      // the command (below).
      for (int k = 0; k < mo.horizon; ++k) {
        bounds.at_s(std::min(s_end, s + rate * stage_end[k]), stage_nom[k], stage_lo[k], stage_hi[k]);
      }
      for (int j = 0; j < n; ++j) {
        const double l = std::max(stage_lo[0][j], lo[j]), u = std::min(stage_hi[0][j], hi[j]);
        if (l <= u) {
          stage_lo[0][j] = l;
          stage_hi[0][j] = u;
        }
      }
      for (int j = 0; j < n; ++j) {
        double a = 0;
        if (options.controller == ControllerKind::kMpc) {
          for (int k = 0; k < mo.horizon; ++k) {
            const double margin = std::min(options.plan_margin, 0.25 * (stage_hi[k][j] - stage_lo[k][j]));
            lower[k] = stage_lo[k][j] + margin;
            upper[k] = stage_hi[k][j] - margin;
            ref[k] = std::clamp(stage_nom[k][j] + dev[j] + dev_rate[j] * stage_end[k], lower[k], upper[k]);
          }
          a = mpcs[j].solve(qc[j], vc[j], ref, lower, upper).accel[0];
        } else {
          // The baseline: the admitted target clamped into the next box, reached as fast as the
          // limits allow.
          const int k = 0;
          const double margin = std::min(options.plan_margin, 0.25 * (stage_hi[k][j] - stage_lo[k][j]));
          const double low = stage_lo[k][j] + margin, high = stage_hi[k][j] - margin;
          const double goal = std::clamp(stage_nom[k][j] + dev[j], low, high);
          // No faster toward a bound than can stop at it: v^2 <= 2 a_max d, in discrete time.
          const double ah = options.max_accel * hc;
          const auto stop_speed = [&](double room) {
            return -ah + std::sqrt(ah * ah + 2 * options.max_accel * std::max(0.0, room));
          };
          const double v_goal = std::clamp((goal - qc[j]) / hc, std::max(-vmax[j], -stop_speed(qc[j] - low)),
                                           std::min(vmax[j], stop_speed(high - qc[j])));
          a = std::clamp((v_goal - vc[j]) / hc, -options.max_accel, options.max_accel);
        }
        ac[j] = a;
      }
      // The safety filter: each joint's acceleration is the one nearest the controller's that keeps
      // the command inside the box at the current s with room to stop there (its stopping point at
      // full deceleration inside the box), within the speed and acceleration limits. So the command
      // can always stay inside the box, whatever the path's progress does next.
      bool stop_inside_now = true;
      for (int j = 0; j < n; ++j) {
        const double margin = std::min(options.plan_margin, 0.25 * (hi[j] - lo[j]));
        const double low = lo[j] + margin, high = hi[j] - margin;
        const double a_min = std::max(-options.max_accel, (-vmax[j] - vc[j]) / hc);
        const double a_max = std::min(options.max_accel, (vmax[j] - vc[j]) / hc);
        const auto end_of = [&](double a, double& q1, double& stop) {
          q1 = qc[j] + hc * vc[j] + 0.5 * hc * hc * a;
          const double v1 = vc[j] + hc * a;
          stop = q1 + v1 * std::abs(v1) / (2 * options.max_accel);
        };
        // Both the end and the stopping point grow with a: bisect for the interval of a that keeps
        // both within [low, high].
        const auto first_at_least = [&](double bound) {  // smallest a with end and stop >= bound
          double q1 = 0, stop = 0;
          end_of(a_min, q1, stop);
          if (std::min(q1, stop) >= bound) return a_min;
          end_of(a_max, q1, stop);
          if (std::min(q1, stop) < bound) return kInf;
          double lo_a = a_min, hi_a = a_max;
          for (int it = 0; it < 50; ++it) {
            const double mid = 0.5 * (lo_a + hi_a);
            end_of(mid, q1, stop);
            (std::min(q1, stop) >= bound ? hi_a : lo_a) = mid;
          }
          return hi_a;
        };
        const auto last_at_most = [&](double bound) {  // largest a with end and stop <= bound
          double q1 = 0, stop = 0;
          end_of(a_max, q1, stop);
          if (std::max(q1, stop) <= bound) return a_max;
          end_of(a_min, q1, stop);
          if (std::max(q1, stop) > bound) return -kInf;
          double lo_a = a_min, hi_a = a_max;
          for (int it = 0; it < 50; ++it) {
            const double mid = 0.5 * (lo_a + hi_a);
            end_of(mid, q1, stop);
            (std::max(q1, stop) <= bound ? lo_a : hi_a) = mid;
          }
          return lo_a;
        };
        const double from = first_at_least(low), to = last_at_most(high);
        if (from <= to) {
          ac[j] = std::clamp(ac[j], from, to);
        } else {
          // No acceleration can (the box is narrower than the motion needs, e.g. a bound of zero
          // width on a moving path): brake toward the box; the clamp below keeps the command in it.
          double q1 = 0, stop = 0;
          end_of(0, q1, stop);
          ac[j] = stop > high ? a_min : a_max;
          stop_inside_now = false;
        }
      }
      // Progress: as far toward the wished s as keeps the command where it will be at the period's
      // end, and its stopping point, inside the box (the path waits for the command).
      const Eigen::VectorXd q_end = qc + hc * vc + 0.5 * hc * hc * ac;
      const Eigen::VectorXd v_end = vc + hc * ac;
      const auto inside = [&](double s_next) {
        bounds.at_s(s_next, n_k, lo_k, hi_k);
        for (int j = 0; j < n; ++j) {
          const double margin = std::min(options.plan_margin, 0.25 * (hi_k[j] - lo_k[j]));
          const double stop = q_end[j] + v_end[j] * std::abs(v_end[j]) / (2 * options.max_accel);
          if (q_end[j] < lo_k[j] || q_end[j] > hi_k[j]) return false;
          if (stop_inside_now && (stop < lo_k[j] + margin || stop > hi_k[j] - margin)) return false;
        }
        return true;
      };
      double reached = target;
      if (!inside(target)) {
        double ok = s, bad = target;
        for (int it = 0; it < 20; ++it) {
          const double mid = 0.5 * (ok + bad);
          (inside(mid) ? ok : bad) = mid;
        }
        reached = ok;
      }
      s_from = s;
      s_to = reached;
      rate_prev = (s_to - s_from) / hc;

      double ratio = 0;
      for (int j = 0; j < n; ++j)
        ratio =
            std::max({ratio, std::abs(ac[j]) / options.max_accel, std::abs(vc[j] + hc * ac[j]) / vmax[j]});
      if (ratio > 1 + 1e-6) ++report.limit_steps;
      report.max_limit_ratio = std::max(report.max_limit_ratio, ratio);

      if (on_frame) {
        SimFrame frame;
        frame.t = t;
        frame.s = s;
        frame.tool = tool;
        frame.force = force;
        frame.box = bounds.at_s(s);
        on_frame(m, d, frame);
      }
    }

    // This substep's progress and command; the command stays in the box at its s (the safety clamp).
    s = s_from + (s_to - s_from) * (sub + 1) / substeps;
    const Eigen::VectorXd lo_before = lo, hi_before = hi;
    bounds.at_s(s, nom, lo, hi);
    qc += dt * vc + 0.5 * dt * dt * ac;
    vc += dt * ac;
    bool clamped = false;
    for (int j = 0; j < n; ++j) {
      // A command outside the box is put on its edge, moving as the edge moves.
      if (qc[j] < lo[j]) {
        qc[j] = lo[j];
        vc[j] = std::max(vc[j], (lo[j] - lo_before[j]) / dt);
        clamped = true;
      } else if (qc[j] > hi[j]) {
        qc[j] = hi[j];
        vc[j] = std::min(vc[j], (hi[j] - hi_before[j]) / dt);
        clamped = true;
      }
    }
    if (clamped) ++report.clamp_steps;
    if (sub + 1 == substeps) {
      // No wind-up: the admitted deviation stays where the bounds let the command go.
      for (int j = 0; j < n; ++j) {
        const double d_lo = lo[j] - nom[j], d_hi = hi[j] - nom[j];
        if (dev[j] < d_lo || dev[j] > d_hi) {
          dev[j] = std::clamp(dev[j], d_lo, d_hi);
          dev_rate[j] = 0;
        }
      }
    }
    if (s >= s_end && reached_at < 0) reached_at = t + dt;
    for (int i = static_cast<int>(std::floor(s_from)) + 1; i <= static_cast<int>(std::floor(s)); ++i)
      if (i < bounds.waypoint_count() && std::isnan(report.waypoint_times[i]))
        report.waypoint_times[i] = t + dt;

    // Measure the state this step starts from (its contacts are mj_step1's).
    {
      Eigen::VectorXd n_now(n), lo_now(n), hi_now(n);
      const double s_now = sub == 0 ? s_from : s_from + (s_to - s_from) * sub / substeps;
      bounds.at_s(s_now, n_now, lo_now, hi_now);
      // The controller's figures count until the first contact: after it, contact forces move the
      // robot, and what follows is the collision's outcome, not the controller's.
      for (int j = 0; j < n && !report.first_contact; ++j) {
        const double out = std::max({0.0, lo_now[j] - q[j], q[j] - hi_now[j]});
        report.max_excursion = std::max(report.max_excursion, out);
        const double dq = q[j] - n_now[j];
        report.max_deviation[j] = std::max(report.max_deviation[j], std::abs(dq));
        const double room = dq >= 0 ? hi_now[j] - n_now[j] : n_now[j] - lo_now[j];
        if (room > 1e-12)
          report.freedom_used[j] = std::max(report.freedom_used[j], std::min(1.0, std::abs(dq) / room));
      }
      bool contact = false;
      const auto near = [&](int g1, int g2, double dist) {
        if (dist <= options.distance_range && (report.min_distance_capped || dist < report.min_distance)) {
          report.min_distance = std::max(0.0, dist);
          report.min_distance_geom1 = scene.geom_label(g1);
          report.min_distance_geom2 = scene.geom_label(g2);
          report.min_distance_t = t;
          report.min_distance_capped = false;
        }
      };
      const auto touch = [&](int g1, int g2, double depth, bool self) {
        contact = true;
        near(g1, g2, 0);
        if (!report.first_contact)
          report.first_contact = SimContact{t, scene.geom_label(g1), scene.geom_label(g2), depth, self};
      };
      // MuJoCo's own contacts (mj_step1's collision at the cell's margins: links against the cell),
      // and MuJoCo's narrowphase on every counted self pair.
      for (int c = 0; c < d.ncon; ++c) {
        const mjContact& con = d.contact[c];
        const bool first_is_link = scene.role(con.geom1) == GeomRole::kLink;
        touch(first_is_link ? con.geom1 : con.geom2, first_is_link ? con.geom2 : con.geom1,
              std::max(0.0, -static_cast<double>(con.dist)), false);
      }
      // Only pairs that may come nearer than the smallest distance so far are measured: the run's
      // minimum is exact, and most pairs are left out after the first steps.
      const auto reach = [&] {
        return report.min_distance_capped ? options.distance_range : report.min_distance;
      };
      for (int g : robot_geoms) take_box(g);
      for (const RobotPair& p : self_pairs) {
        if (geoms_touch(m, d, p.geom1, p.geom2)) {
          touch(p.geom1, p.geom2,
                box_penetration(boxes[static_cast<size_t>(p.geom1)], boxes[static_cast<size_t>(p.geom2)]),
                true);
        } else if (bound_gap(p.geom1, p.geom2) <= reach()) {
          near(p.geom1, p.geom2,
               box_distance(boxes[static_cast<size_t>(p.geom1)], boxes[static_cast<size_t>(p.geom2)]));
        }
      }
      // Distances to the cell: the obstacles whose boxes' bounds come within reach of a link's.
      const StaticGeoms& statics = scene.statics();
      for (int l : scene.link_geoms()) {
        Aabb query = box_bounds[static_cast<size_t>(l)];
        query.lo.array() -= reach();
        query.hi.array() += reach();
        statics.grid.any(query, [&](int i) {
          const int o = statics.geoms[static_cast<size_t>(i)];
          if (scene.role(o) == GeomRole::kObstacle && has_bounding_box(m, o) && bound_gap(l, o) <= reach())
            near(l, o, box_distance(boxes[static_cast<size_t>(l)], boxes[static_cast<size_t>(o)]));
          return false;
        });
      }
      if (contact) ++report.contact_steps;
    }

    if (sub != 0) push_on_joints();
    // The servo: computed torque from the model (M a + bias - passive), minus the push that the
    // wrist's force sensor measures, so the push moves the robot only through the admittance.
    for (int i = 0; i < m.nv; ++i) acc[i] = -kd * d.qvel[i];  // joints outside the robot: held still
    double tracking = 0;
    for (int j = 0; j < n; ++j) {
      acc[vadr[j]] = ac[j] + kp * (qc[j] - q[j]) + kd * (vc[j] - v[j]);
      tracking = std::max(tracking, std::abs(qc[j] - q[j]));
    }
    if (!report.first_contact) report.max_tracking_error = std::max(report.max_tracking_error, tracking);
    mj_mulM(&m, &d, mass_acc.data(), acc.data());
    // MuJoCo's Euler step integrates joint damping implicitly, (M + dt D) qacc = force: add dt D a.
    for (int i = 0; i < m.nv; ++i)
      d.qfrc_applied[i] =
          mass_acc[i] + dt * m.dof_damping[i] * acc[i] + d.qfrc_bias[i] - d.qfrc_passive[i] - human_gen[i];
    // The push itself, applied at the tool site: MuJoCo's xfrc_applied acts at the body's centre of mass.
    const Eigen::Vector3d com(d.xipos[3 * tool_body], d.xipos[3 * tool_body + 1], d.xipos[3 * tool_body + 2]);
    const Eigen::Vector3d moment = torque + (tool - com).cross(force);
    for (int r = 0; r < 3; ++r) {
      d.xfrc_applied[6 * tool_body + r] = force[r];
      d.xfrc_applied[6 * tool_body + 3 + r] = moment[r];
    }
    mj_step2(&m, &d);
    ++report.steps;
    if (reached_at >= 0 && t + dt >= reached_at + options.end_hold) break;
  }
  report.simulated_time = static_cast<double>(report.steps) * dt;
  report.reached_end = reached_at >= 0;
  report.end_time = report.reached_end ? reached_at : report.simulated_time;
  report.left_bounds = report.max_excursion > 0;
  report.rms_force = force_samples ? std::sqrt(force_sq_sum / static_cast<double>(force_samples)) : 0;
  report.wall_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return report;
}

const char* human_kind_name(HumanKind kind) {
  switch (kind) {
    case HumanKind::kNone:
      return "none";
    case HumanKind::kRandom:
      return "random";
    case HumanKind::kPushToward:
      return "push-toward";
    case HumanKind::kFile:
      return "file";
  }
  return "?";
}

nlohmann::json simulation_json(const Scene& scene, const SimulationReport& r, const SimulateOptions& o,
                               const std::string& cell, const std::string& bounds) {
  using nlohmann::json;
  const auto vec = [](const Eigen::VectorXd& v) {
    json a = json::array();
    for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(v[i]);
    return a;
  };
  json waypoints = json::array();
  for (double t : r.waypoint_times) waypoints.push_back(std::isnan(t) ? json(nullptr) : json(t));
  json human = {{"kind", human_kind_name(o.human.kind)}};
  if (o.human.kind == HumanKind::kRandom)
    human.update({{"amplitude", o.human.amplitude}, {"bandwidth", o.human.bandwidth}, {"seed", o.seed}});
  if (o.human.kind == HumanKind::kPushToward)
    human.update({{"amplitude", o.human.amplitude}, {"target", o.human.target}});
  if (o.human.kind == HumanKind::kFile) human["samples"] = o.human.samples.size();
  human.update({{"rms_force", r.rms_force}, {"max_force", r.max_force}});
  json controller = {{"kind", o.controller == ControllerKind::kMpc ? "mpc" : "projection"},
                     {"period", o.control_period},
                     {"max_accel", o.max_accel},
                     {"speed_scale", o.speed_scale},
                     {"plan_margin", o.plan_margin},
                     {"servo_bandwidth", o.servo_bandwidth},
                     {"admittance", {{"inertia", o.admittance_inertia}, {"damping", o.admittance_damping}}},
                     {"hold_force", o.hold_force}};
  if (o.controller == ControllerKind::kMpc)
    controller["mpc"] = {{"horizon", o.mpc.horizon},
                         {"first_period", o.mpc.first_period},
                         {"period", o.mpc.period},
                         {"accel_weight", o.mpc.accel_weight},
                         {"iterations", o.mpc.iterations}};
  json contact = nullptr;
  if (r.first_contact)
    contact = {{"t", r.first_contact->t},
               {"geom1", r.first_contact->geom1},
               {"geom2", r.first_contact->geom2},
               {"depth", r.first_contact->depth},
               {"self", r.first_contact->self}};
  json min_distance = {{"value", r.min_distance}, {"capped", r.min_distance_capped}};
  if (!r.min_distance_capped)
    min_distance.update(
        {{"t", r.min_distance_t}, {"geom1", r.min_distance_geom1}, {"geom2", r.min_distance_geom2}});
  return {{"format", "leeway-simulation-1"},
          {"units", "SI: s, m, rad (m for slide joints), N, N m; shares are fractions"},
          {"cell", cell},
          {"bounds", bounds},
          {"joints", scene.joint_names()},
          {"speed", o.speed},
          {"human", human},
          {"controller", controller},
          {"timestep", r.timestep},
          {"steps", r.steps},
          {"simulated_time", r.simulated_time},
          {"nominal_duration", r.nominal_duration},
          {"reached_end", r.reached_end},
          {"end_time", r.end_time},
          {"waypoint_times", waypoints},
          {"contacts", r.contact_steps},
          {"first_contact", contact},
          {"min_distance", min_distance},
          {"left_bounds", r.left_bounds},
          {"max_excursion", r.max_excursion},
          {"clamp_steps", r.clamp_steps},
          {"limit_periods", r.limit_steps},
          {"max_limit_ratio", r.max_limit_ratio},
          {"freedom_used", vec(r.freedom_used)},
          {"max_deviation", vec(r.max_deviation)},
          {"max_tracking_error", r.max_tracking_error},
          {"wall_time", r.wall_time},
          {"wall_per_simulated_second", r.simulated_time > 0 ? r.wall_time / r.simulated_time : 0.0}};
}

}  // namespace leeway
