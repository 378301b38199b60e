#include "leeway/path/planner.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <deque>
#include <fstream>
#include <memory>
#include <mutex>

#include <ompl/base/MotionValidator.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/ScopedState.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/StateValidityChecker.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/config.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/PathSimplifier.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>

#include "core/json_io.hpp"
#include "core/random.hpp"
#include "leeway/core/box.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/shape.hpp"

namespace leeway {
namespace {

namespace ob = ompl::base;
namespace og = ompl::geometric;
using nlohmann::json;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Independent, well-mixed 32-bit seeds for the planner's random streams from one user seed (OMPL's
// RNG takes 32 bits; 0 is avoided, OMPL rejects it as a global seed).
std::uint32_t stream_seed(std::uint64_t seed, std::uint64_t stream) {
  const auto s = static_cast<std::uint32_t>(detail::splitmix(seed + 0x9e3779b97f4a7c15ULL * stream) >> 32);
  return s == 0 ? 1u : s;
}

// The step of every joint: `resolution` for hinges, `slide_resolution` for slides.
Eigen::VectorXd joint_steps(const Scene& scene, double resolution, double slide_resolution) {
  Eigen::VectorXd step(scene.dof());
  for (int i = 0; i < scene.dof(); ++i)
    step[i] = scene.joints()[static_cast<size_t>(i)].prismatic ? slide_resolution : resolution;
  return step;
}

// Segments of the edge a -> b such that no joint moves more than its step between samples (the
// 1e-9 keeps 3 / 0.01 = 300.00000000000006 at 300 segments).
long edge_segments(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const Eigen::VectorXd& step) {
  const double m = ((b - a).cwiseAbs().array() / step.array()).maxCoeff();
  return std::max(1L, static_cast<long>(std::ceil(m - 1e-9)));
}

Eigen::VectorXd lerp(const Eigen::VectorXd& a, const Eigen::VectorXd& b, long k, long n) {
  if (k == n) return b;
  return a + (b - a) * (static_cast<double>(k) / static_cast<double>(n));
}

// RobotState::clearance(q).distance >= margin at the configuration last set, but quicker: most
// link-obstacle pairs are ruled out by two lower bounds of their distance (bounding spheres, then,
// for two boxes, the separating-axis gap) before the exact distance of their shapes is needed.
bool keeps_clearance(const RobotState& state, double margin) {
  const Scene& scene = state.scene();
  const mjModel& m = scene.model();
  const mjData& d = state.data();
  for (int o : scene.obstacle_geoms()) {
    if (m.geom_type[o] == mjGEOM_PLANE) continue;  // as RobotState::clearance
    const Shape ob = geom_shape(m, d, o);
    for (int l : scene.link_geoms()) {
      const Shape lb = geom_shape(m, d, l);
      if ((lb.box.center - ob.box.center).norm() - lb.radius - ob.radius >= margin) continue;
      if (lb.is_box() && ob.is_box() && -box_penetration(lb.box, ob.box) >= margin) continue;
      if (shape_distance(lb, ob) < margin) return false;
    }
  }
  return true;
}

// A configuration is free when it is within the limits, touches no obstacle and, with a margin,
// keeps at least that clearance.
bool configuration_free(RobotState& state, const Eigen::VectorXd& q, double clearance) {
  if (!state.scene().joints_outside_limits(q).empty()) return false;
  if (state.in_collision(q)) return false;  // also sets the kinematics for keeps_clearance
  return clearance <= 0 || keeps_clearance(state, clearance);
}

// RobotStates for the threads that check configurations: one mjData per concurrent caller.
class StatePool {
 public:
  explicit StatePool(const Scene& scene) : scene_(&scene) {}

  //! A RobotState borrowed for one check; returned to the pool when the lease dies.
  class Lease {
   public:
    Lease(StatePool& pool, std::unique_ptr<RobotState> s) : pool_(&pool), state_(std::move(s)) {}
    ~Lease() { pool_->give_back(std::move(state_)); }
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;
    RobotState& operator*() const { return *state_; }

   private:
    StatePool* pool_;
    std::unique_ptr<RobotState> state_;
  };

  Lease lease() {
    std::unique_ptr<RobotState> s;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!free_.empty()) {
        s = std::move(free_.back());
        free_.pop_back();
      }
    }
    if (!s) s = std::make_unique<RobotState>(*scene_);
    return Lease(*this, std::move(s));
  }

 private:
  void give_back(std::unique_ptr<RobotState> s) {
    std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(std::move(s));
  }
  const Scene* scene_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<RobotState>> free_;
};

// Everything OMPL's callbacks need: the conversion between OMPL's coordinates and joint values,
// and the collision checks. OMPL plans in joint values divided by their step (resolution or
// slide_resolution), so that its Euclidean metric weighs one metre of a slide like
// resolution / slide_resolution radians of a hinge, and one unit is one collision-check step.
class Checker {
 public:
  Checker(const Scene& scene, Eigen::VectorXd step, double clearance)
      : scene_(&scene),
        step_(std::move(step)),
        lower_(scene.lower_limits()),
        upper_(scene.upper_limits()),
        clearance_(clearance),
        pool_(scene) {}

  Eigen::VectorXd to_q(const ob::State* s) const {
    const double* x = s->as<ob::RealVectorStateSpace::StateType>()->values;
    Eigen::VectorXd q(scene_->dof());
    // Clamped: x * step can leave the limits by an ulp.
    for (int i = 0; i < scene_->dof(); ++i) q[i] = std::clamp(x[i] * step_[i], lower_[i], upper_[i]);
    return q;
  }
  void to_state(const Eigen::VectorXd& q, ob::State* s) const {
    double* x = s->as<ob::RealVectorStateSpace::StateType>()->values;
    for (int i = 0; i < scene_->dof(); ++i) x[i] = q[i] / step_[i];
  }

  bool free(const Eigen::VectorXd& q) {
    ++checks_;
    auto state = pool_.lease();
    return configuration_free(*state, q, clearance_);
  }

  // The edge a -> b at the resolution, `a` assumed free (OMPL's convention). The far end first,
  // then the samples in bisection order: a blocked edge is usually found after few checks.
  bool edge_free(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    const long n = edge_segments(a, b, step_);
    if (!free(b)) return false;
    std::deque<std::pair<long, long>> intervals{{0, n}};
    while (!intervals.empty()) {
      const auto [lo, hi] = intervals.front();
      intervals.pop_front();
      if (hi - lo < 2) continue;
      const long mid = lo + (hi - lo) / 2;
      if (!free(lerp(a, b, mid, n))) return false;
      intervals.emplace_back(lo, mid);
      intervals.emplace_back(mid, hi);
    }
    return true;
  }

  // The edge a -> b in order from a; on failure the last free sample and its fraction of the edge.
  bool edge_free_from(const Eigen::VectorXd& a, const Eigen::VectorXd& b, long& last_free, long& segments) {
    segments = edge_segments(a, b, step_);
    for (long k = 1; k <= segments; ++k)
      if (!free(lerp(a, b, k, segments))) {
        last_free = k - 1;
        return false;
      }
    return true;
  }

  long checks() const { return checks_.load(); }
  const Eigen::VectorXd& step() const { return step_; }

 private:
  const Scene* scene_;
  Eigen::VectorXd step_, lower_, upper_;
  double clearance_;
  StatePool pool_;
  std::atomic<long> checks_{0};
};

class ValidityChecker : public ob::StateValidityChecker {
 public:
  ValidityChecker(const ob::SpaceInformationPtr& si, std::shared_ptr<Checker> checker)
      : ob::StateValidityChecker(si), checker_(std::move(checker)) {}
  bool isValid(const ob::State* s) const override { return checker_->free(checker_->to_q(s)); }

 private:
  std::shared_ptr<Checker> checker_;
};

// Replaces OMPL's DiscreteMotionValidator (whose resolution is a fraction of the space's diagonal,
// in the Euclidean metric) by leeway's per-joint criterion, so that the planner, the simplifier and
// edge_is_free() agree on what a free edge is.
class MotionValidator : public ob::MotionValidator {
 public:
  MotionValidator(const ob::SpaceInformationPtr& si, std::shared_ptr<Checker> checker)
      : ob::MotionValidator(si), checker_(std::move(checker)) {}

  bool checkMotion(const ob::State* s1, const ob::State* s2) const override {
    ++motions_;
    return checker_->edge_free(checker_->to_q(s1), checker_->to_q(s2));
  }

  bool checkMotion(const ob::State* s1, const ob::State* s2,
                   std::pair<ob::State*, double>& last_valid) const override {
    ++motions_;
    long last = 0, n = 1;
    if (checker_->edge_free_from(checker_->to_q(s1), checker_->to_q(s2), last, n)) return true;
    last_valid.second = static_cast<double>(last) / static_cast<double>(n);
    if (last_valid.first != nullptr)
      si_->getStateSpace()->interpolate(s1, s2, last_valid.second, last_valid.first);
    return false;
  }

  //! Motions checked so far: an upper bound of the states RRT-Connect added to its trees.
  long motions() const { return motions_.load(); }

 private:
  std::shared_ptr<Checker> checker_;
  mutable std::atomic<long> motions_{0};
};

// OMPL's RNG instances draw their seeds from one process-wide sequence, and RNG::setSeed() may
// only be called before the first RNG exists (later calls log an error). Instead, every random
// stream of a plan gets its own seed from PlanOptions::seed: the state samplers, RRT-Connect's and
// the simplifier's generators. (The nearest-neighbour structure's random pivots change its speed,
// not its answers: its queries are exact.)
class SeededSampler : public ob::RealVectorStateSampler {
 public:
  SeededSampler(const ob::StateSpace* space, std::uint32_t seed) : ob::RealVectorStateSampler(space) {
    rng_.setLocalSeed(seed);
  }
};

class SeededRRTConnect : public og::RRTConnect {
 public:
  SeededRRTConnect(const ob::SpaceInformationPtr& si, std::uint32_t seed) : og::RRTConnect(si) {
    rng_.setLocalSeed(seed);
  }
};

class SeededSimplifier : public og::PathSimplifier {
 public:
  SeededSimplifier(const ob::SpaceInformationPtr& si, std::uint32_t seed) : og::PathSimplifier(si) {
    rng_.setLocalSeed(seed);
  }
};

std::vector<Eigen::VectorXd> to_waypoints(const og::PathGeometric& path, const Checker& checker) {
  std::vector<Eigen::VectorXd> out;
  for (unsigned i = 0; i < path.getStateCount(); ++i) out.push_back(checker.to_q(path.getState(i)));
  return out;
}

// The whole path at the resolution, each edge from its start.
bool path_free(Checker& checker, const std::vector<Eigen::VectorXd>& path) {
  if (path.empty() || !checker.free(path.front())) return false;
  for (std::size_t i = 1; i < path.size(); ++i)
    if (!checker.edge_free(path[i - 1], path[i])) return false;
  return true;
}

double weighted_length(const std::vector<Eigen::VectorXd>& path, const Eigen::VectorXd& step,
                       double resolution) {
  double length = 0;
  for (std::size_t i = 1; i < path.size(); ++i)
    length += ((path[i] - path[i - 1]).array() / step.array()).matrix().norm() * resolution;
  return length;
}

void validate(const PlanOptions& o) {
  auto finite_positive = [](double v, const std::string& what, double lo, double hi, const char* unit) {
    if (!(std::isfinite(v) && v >= lo && v <= hi))
      throw InputError("plan option '" + what + "' = " + format_number(v) + " " + unit +
                       " must be a finite number from " + format_number(lo) + " to " + format_number(hi));
  };
  finite_positive(o.time_limit, "time_limit", 1e-3, 86400, "s");
  finite_positive(o.resolution, "resolution", 1e-5, 1.0, "rad");
  finite_positive(o.slide_resolution, "slide_resolution", 1e-5, 1.0, "m");
  if (o.max_states < 16 || o.max_states > kMaxPlanStates)
    throw InputError("plan option 'max_states' = " + std::to_string(o.max_states) + " must be from 16 to " +
                     std::to_string(kMaxPlanStates) + " (the memory limit of RRT-Connect's trees)");
  if (!(std::isfinite(o.range) && o.range >= 0))
    throw InputError("plan option 'range' = " + format_number(o.range) +
                     " rad must be a finite number >= 0 (0: OMPL's default)");
  if (!(std::isfinite(o.clearance) && o.clearance >= 0 && o.clearance <= 10))
    throw InputError("plan option 'clearance' = " + format_number(o.clearance) +
                     " m must be a finite number from 0 to 10");
}

// OMPL logs to the console: keep its warnings and errors, drop its progress messages, but only
// while a plan_path call runs. OMPL's level is process-wide, so overlapping calls (threads) share
// one change: the first to enter lowers the noise, the last to leave restores the caller's level.
class QuietOmpl {
 public:
  QuietOmpl() {
    std::lock_guard<std::mutex> lock(mutex());
    if (depth()++ == 0) {
      saved() = ompl::msg::getLogLevel();
      if (saved() < ompl::msg::LOG_WARN) ompl::msg::setLogLevel(ompl::msg::LOG_WARN);
    }
  }
  ~QuietOmpl() {
    std::lock_guard<std::mutex> lock(mutex());
    if (--depth() == 0) ompl::msg::setLogLevel(saved());
  }
  QuietOmpl(const QuietOmpl&) = delete;
  QuietOmpl& operator=(const QuietOmpl&) = delete;

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  static int& depth() {
    static int d = 0;
    return d;
  }
  static ompl::msg::LogLevel& saved() {
    static ompl::msg::LogLevel level = ompl::msg::LOG_INFO;
    return level;
  }
};

}  // namespace

void require_free(RobotState& state, const Eigen::VectorXd& q, double clearance, const std::string& what) {
  const Scene& scene = state.scene();
  scene.validate_configuration(q, what);
  for (int i : scene.joints_outside_limits(q)) {
    const RobotJoint& j = scene.joints()[static_cast<size_t>(i)];
    const char* unit = j.prismatic ? " m" : " rad";
    throw InputError(what + ": joint '" + j.name + "' = " + format_number(q[i]) + unit +
                     " is outside its limits [" + format_number(j.lower) + ", " + format_number(j.upper) +
                     "]" + unit);
  }
  const auto contacts = state.contacts(q);
  if (!contacts.empty())
    throw InputError(
        what + " is in collision: link '" + scene.geom_label(contacts[0].link_geom) +
        "' penetrates obstacle '" + scene.geom_label(contacts[0].obstacle_geom) + "' by " +
        format_number(contacts[0].depth) + " m" +
        (contacts.size() > 1 ? " (and " + std::to_string(contacts.size() - 1) + " more contacts)" : ""));
  const auto self = state.self_contacts(q);
  if (!self.empty())
    throw InputError(
        what + " is in self-collision: robot geoms '" + scene.geom_label(self[0].geom1) + "' and '" +
        scene.geom_label(self[0].geom2) + "' overlap by " + format_number(self[0].depth) + " m" +
        (self.size() > 1 ? " (and " + std::to_string(self.size() - 1) + " more self pairs)" : ""));
  if (clearance > 0) {
    const Clearance c = state.clearance(q);
    if (c.distance < clearance)
      throw InputError(what + " is " + format_number(c.distance) + " m from obstacle '" +
                       scene.geom_label(c.obstacle_geom) + "' (link '" + scene.geom_label(c.link_geom) +
                       "'), closer than the clearance margin " + format_number(clearance) + " m");
  }
}

bool edge_is_free(RobotState& state, const Eigen::VectorXd& a, const Eigen::VectorXd& b, double resolution,
                  double slide_resolution, double clearance, long& checks) {
  const Scene& scene = state.scene();
  scene.validate_configuration(a, "edge start");
  scene.validate_configuration(b, "edge end");
  if (!(resolution > 0 && slide_resolution > 0))
    throw InputError("edge check: the resolutions must be > 0, got " + format_number(resolution) +
                     " rad and " + format_number(slide_resolution) + " m");
  const Eigen::VectorXd step = joint_steps(scene, resolution, slide_resolution);
  const long n = edge_segments(a, b, step);
  for (long k = 0; k <= n; ++k) {
    ++checks;
    if (!configuration_free(state, lerp(a, b, k, n), clearance)) return false;
  }
  return true;
}

PlanResult plan_path(const Scene& scene, const Eigen::VectorXd& start, const Eigen::VectorXd& goal,
                     const PlanOptions& options, const std::string& start_name,
                     const std::string& goal_name) {
  validate(options);
  {
    RobotState state(scene);
    require_free(state, start, options.clearance, scene.source() + ": " + start_name);
    require_free(state, goal, options.clearance, scene.source() + ": " + goal_name);
  }
  const QuietOmpl quiet;  // restores OMPL's log level when plan_path returns or throws
  const auto t0 = std::chrono::steady_clock::now();
  const int n = scene.dof();
  auto checker = std::make_shared<Checker>(
      scene, joint_steps(scene, options.resolution, options.slide_resolution), options.clearance);
  PlanResult result;

  // The straight joint-space edge, when free, is the shortest path in the planner's metric: no
  // sampling needed (our reading: the thesis's own nominal paths between keyframes are such edges).
  if (options.try_direct && checker->edge_free(start, goal)) {
    result.success = true;
    result.method = "direct";
    result.waypoints = {start, goal};
    result.raw_waypoints = 2;
    result.plan_seconds = seconds_since(t0);
    result.length = weighted_length(result.waypoints, checker->step(), options.resolution);
    result.checks = checker->checks();
    return result;
  }

  auto space = std::make_shared<ob::RealVectorStateSpace>(static_cast<unsigned>(n));
  ob::RealVectorBounds bounds(static_cast<unsigned>(n));
  for (int i = 0; i < n; ++i) {
    const RobotJoint& j = scene.joints()[static_cast<size_t>(i)];
    bounds.setLow(static_cast<unsigned>(i), j.lower / checker->step()[i]);
    bounds.setHigh(static_cast<unsigned>(i), j.upper / checker->step()[i]);
  }
  space->setBounds(bounds);
  auto samplers = std::make_shared<std::atomic<std::uint64_t>>(0);
  const std::uint64_t seed = options.seed;
  space->setStateSamplerAllocator([seed, samplers](const ob::StateSpace* s) -> ob::StateSamplerPtr {
    return std::make_shared<SeededSampler>(s, stream_seed(seed, 100 + (*samplers)++));
  });
  auto si = std::make_shared<ob::SpaceInformation>(space);
  si->setStateValidityChecker(std::make_shared<ValidityChecker>(si, checker));
  auto motion_validator = std::make_shared<MotionValidator>(si, checker);
  si->setMotionValidator(motion_validator);
  si->setup();

  ob::ScopedState<> s(space), g(space);
  checker->to_state(start, s.get());
  checker->to_state(goal, g.get());
  auto pdef = std::make_shared<ob::ProblemDefinition>(si);
  pdef->setStartAndGoalStates(s, g);
  auto planner = std::make_shared<SeededRRTConnect>(si, stream_seed(seed, 1));
  if (options.range > 0) planner->setRange(options.range / options.resolution);
  planner->setProblemDefinition(pdef);
  planner->setup();
  const long max_states = options.max_states;
  const ob::PlannerStatus status = planner->solve(ob::plannerOrTerminationCondition(
      ob::timedPlannerTerminationCondition(options.time_limit),
      ob::PlannerTerminationCondition([&] { return motion_validator->motions() >= max_states; })));
  result.method = "rrt_connect";
  result.plan_seconds = seconds_since(t0);
  if (status != ob::PlannerStatus::EXACT_SOLUTION && motion_validator->motions() >= max_states) {
    result.checks = checker->checks();
    result.message = "no collision-free path from " + start_name + " to " + goal_name + " found in " +
                     std::to_string(max_states) + " motions (seed " + std::to_string(options.seed) +
                     "): planning stopped there to keep RRT-Connect's trees within their memory limit "
                     "(about 200 bytes per state)";
    return result;
  }
  if (status != ob::PlannerStatus::EXACT_SOLUTION) {
    result.checks = checker->checks();
    result.message = "no collision-free path from " + start_name + " to " + goal_name +
                     " found within the time limit of " + format_number(options.time_limit) + " s (seed " +
                     std::to_string(options.seed) + "); try a longer time limit or another seed" +
                     (options.clearance > 0 ? std::string(", or a smaller clearance") : std::string());
    return result;
  }

  const auto t1 = std::chrono::steady_clock::now();
  const og::PathGeometric raw = *std::static_pointer_cast<og::PathGeometric>(pdef->getSolutionPath());
  result.raw_waypoints = raw.getStateCount();
  // The exact end configurations: the conversion to OMPL's coordinates and back may move them by
  // an ulp.
  auto finish = [&](std::vector<Eigen::VectorXd> w) {
    if (w.size() < 2) w.resize(2);  // a path is at least its two ends (start == goal)
    w.front() = start;
    w.back() = goal;
    return w;
  };
  std::vector<Eigen::VectorXd> waypoints = finish(to_waypoints(raw, *checker));
  if (options.simplify) {
    og::PathGeometric simple = raw;
    SeededSimplifier simplifier(si, stream_seed(seed, 2));
    // simplifyMax: no time limit, so the result depends on the seed only.
    simplifier.simplifyMax(simple);
    // Re-check the simplified path edge by edge with leeway's criterion; OMPL's repair step may
    // move a state without checking its edges, and then RRT-Connect's checked path is kept.
    std::vector<Eigen::VectorXd> w = finish(to_waypoints(simple, *checker));
    if (path_free(*checker, w)) {
      waypoints = std::move(w);
      result.simplified = true;
    }
  }
  LEEWAY_DEMAND(result.simplified || path_free(*checker, waypoints));
  result.simplify_seconds = seconds_since(t1);
  result.success = true;
  result.waypoints = std::move(waypoints);
  result.length = weighted_length(result.waypoints, checker->step(), options.resolution);
  result.checks = checker->checks();
  return result;
}

}  // namespace leeway
