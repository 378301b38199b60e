#include "leeway/core/simulate.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include "leeway/core/box.hpp"
#include "leeway/core/collision.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/shape.hpp"
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
  require_range(distance_range, 0, 10, "distance range", "m", true);
  require_range(end_hold, 0, 3600, "end hold", "s");
  require_range(max_time, 0, 36000, "max time", "s");
}

namespace {

// One joint's acceleration interval that keeps, after a period of length h from (q, v) at constant
// acceleration, both the position and the stopping point (where braking at a_max would bring it to
// rest) within [low, high], with |a| <= a_max and |v'| <= v_max. Both grow with a, so each end of the
// interval is found by bisection. Empty (from > to) when no acceleration can.
struct AccelInterval {
  double from = 0, to = 0;
  double a_min = 0, a_max = 0;  // the limits' interval
};

AccelInterval stay_and_stop_within(double q, double v, double h, double low, double high, double v_max,
                                   double a_max) {
  AccelInterval r;
  r.a_min = std::max(-a_max, (-v_max - v) / h);
  r.a_max = std::min(a_max, (v_max - v) / h);
  const auto end_and_stop = [&](double a) {
    const double q1 = q + h * v + 0.5 * h * h * a;
    const double v1 = v + h * a;
    return std::pair<double, double>{q1, q1 + v1 * std::abs(v1) / (2 * a_max)};
  };
  const auto lowest = [&](double a) {
    const auto [q1, stop] = end_and_stop(a);
    return std::min(q1, stop);
  };
  const auto highest = [&](double a) {
    const auto [q1, stop] = end_and_stop(a);
    return std::max(q1, stop);
  };
  // The smallest a with both >= low.
  if (lowest(r.a_min) >= low) {
    r.from = r.a_min;
  } else if (lowest(r.a_max) < low) {
    r.from = kInf;
  } else {
    double bad = r.a_min, ok = r.a_max;
    for (int it = 0; it < 50; ++it) {
      const double mid = 0.5 * (bad + ok);
      (lowest(mid) >= low ? ok : bad) = mid;
    }
    r.from = ok;
  }
  // The largest a with both <= high.
  if (highest(r.a_max) <= high) {
    r.to = r.a_max;
  } else if (highest(r.a_min) > high) {
    r.to = -kInf;
  } else {
    double ok = r.a_min, bad = r.a_max;
    for (int it = 0; it < 50; ++it) {
      const double mid = 0.5 * (ok + bad);
      (highest(mid) <= high ? ok : bad) = mid;
    }
    r.to = ok;
  }
  return r;
}

// The closed loop's state and its steps; simulate() runs it. The physics step (mj_step1, then the
// controller, the measurements and the servo, then mj_step2) is step(); a control period's work
// (the push, the admittance, the progress and the plan) is start_period().
class ClosedLoop {
 public:
  ClosedLoop(const Scene& scene, const BoundsTrajectory& bounds, const SimulateOptions& options);
  SimulationReport run(const FrameCallback& on_frame);

 private:
  double margin(double low, double high) const { return std::min(options_.plan_margin, 0.25 * (high - low)); }
  Eigen::Vector3d tool_at(const Eigen::VectorXd& q);
  void push_on_joints();
  void start_period(double t, const Eigen::Vector3d& tool);
  double wished_rate();
  void plan(double rate);
  bool filter();
  void progress(double target, bool stop_inside);
  void advance_command(int sub);
  void measure(double t, int sub, const Eigen::VectorXd& q);
  void measure_distances(double t);
  void servo(const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::Vector3d& tool);
  void take_box(int g);
  double bound_gap(int g1, int g2) const;
  double geom_distance(int g1, int g2) const;

  const Scene& scene_;
  const BoundsTrajectory& bounds_;
  const SimulateOptions& options_;
  const int n_;
  ModelPtr model_;
  DataPtr data_, scratch_;  // the simulation; kinematics of nominal configurations
  double dt_ = 0, hc_ = 0;
  int substeps_ = 1;
  std::vector<int> qadr_, vadr_;
  Eigen::VectorXd vmax_;
  int site_ = -1, tool_body_ = -1;
  std::vector<JointMpc> mpcs_;
  Human human_;
  SimulationReport report_;

  // The command (position, speed, acceleration), the admitted deviation and the progress.
  Eigen::VectorXd qc_, vc_, ac_, dev_, dev_rate_;
  double s_ = 0, s_from_ = 0, s_to_ = 0, rate_prev_ = 0, reached_at_ = -1;
  Eigen::VectorXd nom_, lo_, hi_;  // the box at s_
  Eigen::Vector3d force_ = Eigen::Vector3d::Zero(), torque_ = Eigen::Vector3d::Zero();
  double force_sq_sum_ = 0;
  long force_samples_ = 0;
  Eigen::VectorXd human_gen_;  // J^T w over all dofs
  std::vector<mjtNum> jacp_, jacr_, acc_, mass_acc_;

  // The MPC's stages: their ends [s after now] and the boxes at their predicted s.
  Eigen::VectorXd stage_end_;
  std::vector<Eigen::VectorXd> stage_lo_, stage_hi_, stage_nom_;
  Eigen::VectorXd ref_, lower_, upper_, n_k_, lo_k_, hi_k_;

  // The distance measurement's boxes: the cell's taken once, the robot's at every step.
  std::vector<Box> boxes_;
  std::vector<Aabb> box_bounds_;
  std::vector<int> robot_geoms_;
  bool contact_now_ = false;
};

ClosedLoop::ClosedLoop(const Scene& scene, const BoundsTrajectory& bounds, const SimulateOptions& options)
    : scene_(scene),
      bounds_(bounds),
      options_(options),
      n_(scene.dof()),
      model_(mj_copyModel(nullptr, &scene.model())),  // a copy: the scene is not changed
      human_(scene, options.human, options.seed, options.control_period) {
  if (bounds.dof() != n_)
    throw InputError("simulate: the bounds have " + std::to_string(bounds.dof()) + " joints, the cell " +
                     std::to_string(n_));
  mjModel& m = *model_;
  m.opt.integrator = mjINT_EULER;  // mj_step1/mj_step2 need it
  dt_ = m.opt.timestep;
  hc_ = options.control_period;
  substeps_ = static_cast<int>(std::lround(hc_ / dt_));
  if (substeps_ < 1 || std::abs(substeps_ * dt_ - hc_) > 1e-9 * hc_)
    throw InputError("simulate: the control period " + format_number(hc_) +
                     " s is not a multiple of the cell's timestep " + format_number(dt_) + " s (" +
                     scene.source() + ", <option timestep>)");
  data_ = make_data(m);
  scratch_ = make_data(m);
  qadr_.resize(static_cast<size_t>(n_));
  vadr_.resize(static_cast<size_t>(n_));
  vmax_.resize(n_);
  for (int j = 0; j < n_; ++j) {
    const RobotJoint& joint = scene.joints()[static_cast<size_t>(j)];
    qadr_[static_cast<size_t>(j)] = m.jnt_qposadr[joint.id];
    vadr_[static_cast<size_t>(j)] = m.jnt_dofadr[joint.id];
    vmax_[j] = joint.max_speed > 0 ? options.speed_scale * joint.max_speed : options.default_speed;
    JointMpcOptions o = options.mpc;
    o.max_speed = vmax_[j];
    o.max_accel = options.max_accel;
    mpcs_.emplace_back(o);
  }
  site_ = scene.tool_site();
  tool_body_ = m.site_bodyid[site_];

  const auto nv = static_cast<size_t>(m.nv);
  jacp_.resize(3 * nv);
  jacr_.resize(3 * nv);
  acc_.resize(nv);
  mass_acc_.resize(nv);
  human_gen_ = Eigen::VectorXd::Zero(m.nv);
  const JointMpcOptions& mo = options.mpc;
  stage_end_.resize(mo.horizon);
  for (int k = 0; k < mo.horizon; ++k) stage_end_[k] = k ? stage_end_[k - 1] + mo.period : mo.first_period;
  stage_lo_.assign(static_cast<size_t>(mo.horizon), Eigen::VectorXd(n_));
  stage_hi_ = stage_nom_ = stage_lo_;
  ref_.resize(mo.horizon);
  lower_.resize(mo.horizon);
  upper_.resize(mo.horizon);
  n_k_.resize(n_);
  lo_k_.resize(n_);
  hi_k_.resize(n_);

  report_.timestep = dt_;
  report_.nominal_duration = bounds.duration();
  report_.waypoint_times.assign(static_cast<size_t>(bounds.waypoint_count()),
                                std::numeric_limits<double>::quiet_NaN());
  report_.waypoint_times[0] = 0;
  report_.freedom_used = Eigen::VectorXd::Zero(n_);
  report_.max_deviation = Eigen::VectorXd::Zero(n_);
  report_.min_distance = options.distance_range;
  report_.min_distance_capped = true;

  // The start: the first waypoint's nominal configuration, at rest.
  nom_.resize(n_);
  lo_.resize(n_);
  hi_.resize(n_);
  bounds.at_s(0, nom_, lo_, hi_);
  scene.set_qpos(*data_, nom_);
  mj_forward(&m, data_.get());
  qc_ = nom_;
  vc_ = ac_ = dev_ = dev_rate_ = Eigen::VectorXd::Zero(n_);

  boxes_.resize(static_cast<size_t>(m.ngeom));
  box_bounds_.resize(static_cast<size_t>(m.ngeom));
  robot_geoms_ = scene.link_geoms();
  for (const RobotPair& p : scene.self_pairs())
    for (int g : {p.geom1, p.geom2})
      if (std::find(robot_geoms_.begin(), robot_geoms_.end(), g) == robot_geoms_.end())
        robot_geoms_.push_back(g);
  for (int o : scene.obstacle_geoms())
    if (has_bounding_box(m, o)) take_box(o);
}

Eigen::Vector3d ClosedLoop::tool_at(const Eigen::VectorXd& q) {
  scene_.set_qpos(*scratch_, q);
  mj_kinematics(model_.get(), scratch_.get());
  const mjtNum* p = scratch_->site_xpos + 3 * site_;
  return {p[0], p[1], p[2]};
}

// The push's generalized force J^T w at the current state.
void ClosedLoop::push_on_joints() {
  const mjModel& m = *model_;
  mj_jacSite(&m, data_.get(), jacp_.data(), jacr_.data(), site_);
  for (int i = 0; i < m.nv; ++i) {
    double g = 0;
    for (int r = 0; r < 3; ++r)
      g += jacp_[static_cast<size_t>(r * m.nv + i)] * force_[r] +
           jacr_[static_cast<size_t>(r * m.nv + i)] * torque_[r];
    human_gen_[i] = g;
  }
}

void ClosedLoop::start_period(double t, const Eigen::Vector3d& tool) {
  std::tie(force_, torque_) = human_.wrench(t, *data_, tool);
  force_sq_sum_ += force_.squaredNorm();
  ++force_samples_;
  report_.max_force = std::max(report_.max_force, force_.norm());
  push_on_joints();
  // Admittance per joint: M d'' + D d' = (J^T w)_i.
  for (int j = 0; j < n_; ++j) {
    const double tau = human_gen_[vadr_[static_cast<size_t>(j)]];
    dev_rate_[j] += hc_ * (tau - options_.admittance_damping * dev_rate_[j]) / options_.admittance_inertia;
    dev_[j] += hc_ * dev_rate_[j];
  }
  bounds_.at_s(s_, nom_, lo_, hi_);
  const double rate = wished_rate();
  plan(rate);
  const bool stop_inside = filter();
  progress(std::min(bounds_.s_end(), s_ + rate * hc_), stop_inside);

  double ratio = 0;
  for (int j = 0; j < n_; ++j)
    ratio =
        std::max({ratio, std::abs(ac_[j]) / options_.max_accel, std::abs(vc_[j] + hc_ * ac_[j]) / vmax_[j]});
  if (ratio > 1 + 1e-6) ++report_.limit_steps;
  report_.max_limit_ratio = std::max(report_.max_limit_ratio, ratio);
}

// The progress the controller wishes for this period [ds/dt]: the nominal rate times the speed,
// limited so that following the nominal path alone needs at most half of each joint's speed and
// acceleration limits (the rest is the co-worker's), ramping up from the last period's and down to
// a stop at the end, and slowed by a push against the tool's direction of travel.
double ClosedLoop::wished_rate() {
  const double s_end = bounds_.s_end();
  const Eigen::Vector3d ahead = tool_at(bounds_.at_s(std::min(s_end, s_ + 0.01)).nominal) - tool_at(nom_);
  double slow = 1;
  if (ahead.norm() > 1e-9) {
    const double against = std::max(0.0, -force_.dot(ahead.normalized()));
    slow = std::clamp(1 - against / options_.hold_force, 0.0, 1.0);
  }
  // The nominal rate and dq/ds of the segment at s (a segment of zero duration is passed at once).
  const int last = std::max(0, bounds_.waypoint_count() - 2);
  const int i = std::min(static_cast<int>(s_), last);
  const auto& times = bounds_.times();
  const double duration =
      bounds_.waypoint_count() > 1 ? times[static_cast<size_t>(i) + 1] - times[static_cast<size_t>(i)] : 0;
  const double nominal_rate = duration > 0 ? 1.0 / duration : 1e6;
  const Eigen::VectorXd slope = bounds_.waypoint_count() > 1
                                    ? Eigen::VectorXd(bounds_.waypoints()[static_cast<size_t>(i) + 1].q -
                                                      bounds_.waypoints()[static_cast<size_t>(i)].q)
                                    : Eigen::VectorXd::Zero(n_);
  double rate_max = options_.speed * nominal_rate, accel_s = kInf;
  for (int j = 0; j < n_; ++j)
    if (std::abs(slope[j]) > 1e-12) {
      rate_max = std::min(rate_max, 0.5 * vmax_[j] / std::abs(slope[j]));
      accel_s = std::min(accel_s, 0.5 * options_.max_accel / std::abs(slope[j]));
    }
  double rate = std::min(rate_max * slow, rate_prev_ + accel_s * hc_);
  if (std::isfinite(accel_s)) rate = std::min(rate, std::sqrt(2 * accel_s * std::max(0.0, s_end - s_)));
  return std::max(rate, 0.0);
}

// The controller's acceleration per joint (ac_): the MPC over the boxes at the s the wished rate
// predicts, or the projection baseline.
void ClosedLoop::plan(double rate) {
  const JointMpcOptions& mo = options_.mpc;
  const double s_end = bounds_.s_end();
  for (size_t k = 0; k < static_cast<size_t>(mo.horizon); ++k)
    bounds_.at_s(std::min(s_end, s_ + rate * stage_end_[static_cast<Eigen::Index>(k)]), stage_nom_[k],
                 stage_lo_[k], stage_hi_[k]);
  // The first stage also stays in the box at the current s, so that progress can wait for it.
  for (int j = 0; j < n_; ++j) {
    const double l = std::max(stage_lo_[0][j], lo_[j]), u = std::min(stage_hi_[0][j], hi_[j]);
    if (l <= u) {
      stage_lo_[0][j] = l;
      stage_hi_[0][j] = u;
    }
  }
  for (int j = 0; j < n_; ++j) {
    if (options_.controller == ControllerKind::kMpc) {
      for (size_t k = 0; k < static_cast<size_t>(mo.horizon); ++k) {
        const auto e = static_cast<Eigen::Index>(k);
        lower_[e] = stage_lo_[k][j] + margin(stage_lo_[k][j], stage_hi_[k][j]);
        upper_[e] = stage_hi_[k][j] - margin(stage_lo_[k][j], stage_hi_[k][j]);
        ref_[e] = std::clamp(stage_nom_[k][j] + dev_[j] + dev_rate_[j] * stage_end_[e], lower_[e], upper_[e]);
      }
      ac_[j] = mpcs_[static_cast<size_t>(j)].solve(qc_[j], vc_[j], ref_, lower_, upper_).accel[0];
      continue;
    }
    // The baseline: the admitted target clamped into the next box, approached no faster than can
    // stop at the box's edge (v^2 <= 2 a_max d, in discrete time), within the limits.
    const double low = stage_lo_[0][j] + margin(stage_lo_[0][j], stage_hi_[0][j]);
    const double high = stage_hi_[0][j] - margin(stage_lo_[0][j], stage_hi_[0][j]);
    const double goal = std::clamp(stage_nom_[0][j] + dev_[j], low, high);
    const double ah = options_.max_accel * hc_;
    const auto stop_speed = [&](double room) {
      return -ah + std::sqrt(ah * ah + 2 * options_.max_accel * std::max(0.0, room));
    };
    const double v_goal = std::clamp((goal - qc_[j]) / hc_, std::max(-vmax_[j], -stop_speed(qc_[j] - low)),
                                     std::min(vmax_[j], stop_speed(high - qc_[j])));
    ac_[j] = std::clamp((v_goal - vc_[j]) / hc_, -options_.max_accel, options_.max_accel);
  }
}

// The safety filter: each joint's acceleration becomes the one nearest the controller's that keeps
// the command at the period's end, and its stopping point, inside the box at the current s, within
// the limits; so the command can always stay inside the box whatever progress does next. Returns
// false when some joint could not (a box narrower than the motion needs, such as a bound of zero
// width on a moving path): that joint brakes toward the box and the clamp keeps it inside.
bool ClosedLoop::filter() {
  bool stop_inside = true;
  for (int j = 0; j < n_; ++j) {
    const double low = lo_[j] + margin(lo_[j], hi_[j]), high = hi_[j] - margin(lo_[j], hi_[j]);
    const AccelInterval r =
        stay_and_stop_within(qc_[j], vc_[j], hc_, low, high, vmax_[j], options_.max_accel);
    if (r.from <= r.to) {
      ac_[j] = std::clamp(ac_[j], r.from, r.to);
    } else {
      const double v = vc_[j];
      const double stop = qc_[j] + hc_ * v + v * std::abs(v) / (2 * options_.max_accel);
      ac_[j] = stop > high ? r.a_min : r.a_max;
      stop_inside = false;
    }
  }
  return stop_inside;
}

// Progress: as far toward `target` as keeps the command at the period's end, and its stopping point,
// inside the box (the path waits for the command).
void ClosedLoop::progress(double target, bool stop_inside) {
  const Eigen::VectorXd q_end = qc_ + hc_ * vc_ + 0.5 * hc_ * hc_ * ac_;
  const Eigen::VectorXd v_end = vc_ + hc_ * ac_;
  const auto inside = [&](double s_next) {
    bounds_.at_s(s_next, n_k_, lo_k_, hi_k_);
    for (int j = 0; j < n_; ++j) {
      const double stop = q_end[j] + v_end[j] * std::abs(v_end[j]) / (2 * options_.max_accel);
      if (q_end[j] < lo_k_[j] || q_end[j] > hi_k_[j]) return false;
      const double m = margin(lo_k_[j], hi_k_[j]);
      if (stop_inside && (stop < lo_k_[j] + m || stop > hi_k_[j] - m)) return false;
    }
    return true;
  };
  double reached = target;
  if (!inside(target)) {
    double ok = s_, bad = target;
    for (int it = 0; it < 20; ++it) {
      const double mid = 0.5 * (ok + bad);
      (inside(mid) ? ok : bad) = mid;
    }
    reached = ok;
  }
  s_from_ = s_;
  s_to_ = reached;
  rate_prev_ = (s_to_ - s_from_) / hc_;
}

// One physics step's progress and command; a command outside the box at its s is put on the box's
// edge, moving as the edge moves (the clamp); the admitted deviation does not wind up past the box.
void ClosedLoop::advance_command(int sub) {
  s_ = s_from_ + (s_to_ - s_from_) * (sub + 1) / substeps_;
  const Eigen::VectorXd lo_before = lo_, hi_before = hi_;
  bounds_.at_s(s_, nom_, lo_, hi_);
  qc_ += dt_ * vc_ + 0.5 * dt_ * dt_ * ac_;
  vc_ += dt_ * ac_;
  bool clamped = false;
  for (int j = 0; j < n_; ++j) {
    if (qc_[j] < lo_[j]) {
      qc_[j] = lo_[j];
      vc_[j] = std::max(vc_[j], (lo_[j] - lo_before[j]) / dt_);
      clamped = true;
    } else if (qc_[j] > hi_[j]) {
      qc_[j] = hi_[j];
      vc_[j] = std::min(vc_[j], (hi_[j] - hi_before[j]) / dt_);
      clamped = true;
    }
  }
  if (clamped) ++report_.clamp_steps;
  if (sub + 1 == substeps_)
    for (int j = 0; j < n_; ++j) {
      const double d_lo = lo_[j] - nom_[j], d_hi = hi_[j] - nom_[j];
      if (dev_[j] < d_lo || dev_[j] > d_hi) {
        dev_[j] = std::clamp(dev_[j], d_lo, d_hi);
        dev_rate_[j] = 0;
      }
    }
}

// The state a step starts from against the box at its s, then its contacts and distances. The
// controller's figures count until the first contact: after it, contact forces move the robot.
void ClosedLoop::measure(double t, int sub, const Eigen::VectorXd& q) {
  const double s_now = s_from_ + (s_to_ - s_from_) * sub / substeps_;
  bounds_.at_s(s_now, n_k_, lo_k_, hi_k_);
  for (int j = 0; j < n_ && !report_.first_contact; ++j) {
    report_.max_excursion = std::max({report_.max_excursion, lo_k_[j] - q[j], q[j] - hi_k_[j]});
    const double dq = q[j] - n_k_[j];
    report_.max_deviation[j] = std::max(report_.max_deviation[j], std::abs(dq));
    const double room = dq >= 0 ? hi_k_[j] - n_k_[j] : n_k_[j] - lo_k_[j];
    if (room > 1e-12)
      report_.freedom_used[j] = std::max(report_.freedom_used[j], std::min(1.0, std::abs(dq) / room));
  }
  measure_distances(t);
  if (contact_now_) ++report_.contact_steps;
}

void ClosedLoop::take_box(int g) {
  const Box b = geom_box(*model_, *data_, g);
  const Eigen::Vector3d extent = b.rotation.cwiseAbs() * b.half_size;
  boxes_[static_cast<size_t>(g)] = b;
  box_bounds_[static_cast<size_t>(g)] = {b.center - extent, b.center + extent};
}

// The distance of two geoms as MuJoCo collides them (shape.hpp): their boxes' for two boxes.
double ClosedLoop::geom_distance(int g1, int g2) const {
  if (model_->geom_type[g1] == mjGEOM_BOX && model_->geom_type[g2] == mjGEOM_BOX)
    return box_distance(boxes_[static_cast<size_t>(g1)], boxes_[static_cast<size_t>(g2)]);
  return shape_distance(geom_shape(*model_, *data_, g1), geom_shape(*model_, *data_, g2));
}

// A lower bound of the distance between two geoms' boxes: the gap between their bounding boxes.
double ClosedLoop::bound_gap(int g1, int g2) const {
  const Aabb& a = box_bounds_[static_cast<size_t>(g1)];
  const Aabb& b = box_bounds_[static_cast<size_t>(g2)];
  return (a.lo - b.hi).cwiseMax(b.lo - a.hi).cwiseMax(0.0).norm();
}

// MuJoCo's own contacts (mj_step1's collision at the cell's margins: links against the cell) and its
// narrowphase on every counted self pair; the smallest distance from the geoms' boxes, for the pairs
// whose bounding boxes can beat the smallest so far (the run's minimum is exact, and most pairs are
// left out after the first steps).
void ClosedLoop::measure_distances(double t) {
  const mjModel& m = *model_;
  const mjData& d = *data_;
  contact_now_ = false;
  const auto near = [&](int g1, int g2, double dist) {
    if (dist <= options_.distance_range && (report_.min_distance_capped || dist < report_.min_distance)) {
      report_.min_distance = std::max(0.0, dist);
      report_.min_distance_geom1 = scene_.geom_label(g1);
      report_.min_distance_geom2 = scene_.geom_label(g2);
      report_.min_distance_t = t;
      report_.min_distance_capped = false;
    }
  };
  const auto touch = [&](int g1, int g2, double depth, bool self) {
    contact_now_ = true;
    near(g1, g2, 0);
    if (!report_.first_contact)
      report_.first_contact = SimContact{t, scene_.geom_label(g1), scene_.geom_label(g2), depth, self};
  };
  for (int c = 0; c < d.ncon; ++c) {
    const mjContact& con = d.contact[c];
    const bool first_is_link = scene_.role(con.geom1) == GeomRole::kLink;
    touch(first_is_link ? con.geom1 : con.geom2, first_is_link ? con.geom2 : con.geom1,
          std::max(0.0, -static_cast<double>(con.dist)), false);
  }
  const auto reach = [&] {
    return report_.min_distance_capped ? options_.distance_range : report_.min_distance;
  };
  const auto box = [&](int g) -> const Box& { return boxes_[static_cast<size_t>(g)]; };
  for (int g : robot_geoms_) take_box(g);
  for (const RobotPair& p : scene_.self_pairs()) {
    if (geoms_touch(m, d, p.geom1, p.geom2))
      touch(p.geom1, p.geom2, box_penetration(box(p.geom1), box(p.geom2)), true);
    else if (bound_gap(p.geom1, p.geom2) <= reach())
      near(p.geom1, p.geom2, geom_distance(p.geom1, p.geom2));
  }
  const StaticGeoms& statics = scene_.statics();
  for (int l : scene_.link_geoms()) {
    Aabb query = box_bounds_[static_cast<size_t>(l)];
    query.lo.array() -= reach();
    query.hi.array() += reach();
    statics.grid.any(query, [&](int i) {
      const int o = statics.geoms[static_cast<size_t>(i)];
      if (scene_.role(o) == GeomRole::kObstacle && has_bounding_box(m, o) && bound_gap(l, o) <= reach())
        near(l, o, geom_distance(l, o));
      return false;
    });
  }
}

// The servo: computed torque from the model (M a + bias - passive), with the acceleration that puts
// each joint exactly on its next command after MuJoCo's (semi-implicit Euler) step, minus the push
// that the wrist's force sensor measures, so that the push moves the robot only through the
// admittance. The model is its own plant, so the robot is where it is commanded to be until a
// contact's forces act on it. The push itself acts at the tool site.
void ClosedLoop::servo(const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::Vector3d& tool) {
  const mjModel& m = *model_;
  mjData& d = *data_;
  for (int i = 0; i < m.nv; ++i) acc_[static_cast<size_t>(i)] = -d.qvel[i] / dt_;  // other joints: held
  for (int j = 0; j < n_; ++j)
    acc_[static_cast<size_t>(vadr_[static_cast<size_t>(j)])] = (qc_[j] - q[j] - dt_ * v[j]) / (dt_ * dt_);
  mj_mulM(&m, &d, mass_acc_.data(), acc_.data());
  // MuJoCo's Euler step integrates joint damping implicitly, (M + dt D) qacc = force: add dt D a.
  for (int i = 0; i < m.nv; ++i) {
    const auto u = static_cast<size_t>(i);
    d.qfrc_applied[i] =
        mass_acc_[u] + dt_ * m.dof_damping[i] * acc_[u] + d.qfrc_bias[i] - d.qfrc_passive[i] - human_gen_[i];
  }
  // MuJoCo's xfrc_applied acts at the body's centre of mass: move the push there.
  const Eigen::Vector3d com(d.xipos[3 * tool_body_], d.xipos[3 * tool_body_ + 1],
                            d.xipos[3 * tool_body_ + 2]);
  const Eigen::Vector3d moment = torque_ + (tool - com).cross(force_);
  for (int r = 0; r < 3; ++r) {
    d.xfrc_applied[6 * tool_body_ + r] = force_[r];
    d.xfrc_applied[6 * tool_body_ + 3 + r] = moment[r];
  }
}

SimulationReport ClosedLoop::run(const FrameCallback& on_frame) {
  const auto wall_start = std::chrono::steady_clock::now();
  mjModel& m = *model_;
  mjData& d = *data_;
  const double max_time = options_.max_time > 0
                              ? options_.max_time
                              : 3 * bounds_.duration() / options_.speed + options_.end_hold + 5;
  const long total_steps = static_cast<long>(std::ceil(max_time / dt_));
  Eigen::VectorXd q(n_), v(n_);
  for (long step = 0; step < total_steps; ++step) {
    const double t = static_cast<double>(step) * dt_;
    const int sub = static_cast<int>(step % substeps_);
    mj_step1(&m, &d);  // kinematics, contacts, mass matrix and bias forces at the current state
    for (int j = 0; j < n_; ++j) {
      q[j] = d.qpos[qadr_[static_cast<size_t>(j)]];
      v[j] = d.qvel[vadr_[static_cast<size_t>(j)]];
    }
    const Eigen::Vector3d tool(d.site_xpos[3 * site_], d.site_xpos[3 * site_ + 1],
                               d.site_xpos[3 * site_ + 2]);
    if (!report_.first_contact)
      report_.max_tracking_error = std::max(report_.max_tracking_error, (q - qc_).cwiseAbs().maxCoeff());
    if (sub == 0) {
      start_period(t, tool);
      if (on_frame) {
        SimFrame frame;
        frame.t = t;
        frame.s = s_;
        frame.tool = tool;
        frame.force = force_;
        frame.box = bounds_.at_s(s_);
        on_frame(m, d, frame);
      }
    } else {
      push_on_joints();
    }
    measure(t, sub, q);
    advance_command(sub);
    if (s_ >= bounds_.s_end() && reached_at_ < 0) reached_at_ = t + dt_;
    for (int i = static_cast<int>(std::floor(s_from_)) + 1; i <= static_cast<int>(std::floor(s_)); ++i)
      if (i < bounds_.waypoint_count() && std::isnan(report_.waypoint_times[static_cast<size_t>(i)]))
        report_.waypoint_times[static_cast<size_t>(i)] = t + dt_;
    servo(q, v, tool);
    mj_step2(&m, &d);
    ++report_.steps;
    if (reached_at_ >= 0 && t + dt_ >= reached_at_ + options_.end_hold) break;
  }
  report_.simulated_time = static_cast<double>(report_.steps) * dt_;
  report_.reached_end = reached_at_ >= 0;
  report_.end_time = report_.reached_end ? reached_at_ : report_.simulated_time;
  report_.left_bounds = report_.max_excursion > 0;
  report_.rms_force = force_samples_ ? std::sqrt(force_sq_sum_ / static_cast<double>(force_samples_)) : 0;
  report_.wall_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return report_;
}

}  // namespace

SimulationReport simulate(const Scene& scene, const BoundsTrajectory& bounds, const SimulateOptions& options,
                          const FrameCallback& on_frame) {
  options.check();
  return ClosedLoop(scene, bounds, options).run(on_frame);
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
