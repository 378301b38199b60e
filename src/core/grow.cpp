#include "grow.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>
#include <vector>

#include "leeway/core/error.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/room.hpp"
#include "parallel.hpp"

namespace leeway {
namespace {

// The greedy shape grows in rounds: round r tries to widen every side of every grown joint to
// this fraction of the room its one-joint free range leaves there, so that no joint takes the room
// another one needs before every joint had its share (the shares rise together).
const std::vector<double> kRoundFractions = {1.0 / 3.0, 2.0 / 3.0, 1.0};
// The lever shape takes one pass, each side straight to its target: the joints come in the order
// of the cost of their share, and the cheapest is given all it can take first.
const std::vector<double> kLeverFractions = {1.0};
// Random configurations of each probe (besides the corners and centres it always checks).
constexpr int kProbeSamples = 32;
// The probe's bisection stops within this of its limit [rad for hinges, m for slides], and the
// certificate is asked for the probe's limit less twice this: the margin's last millimetre costs
// the certificate most of its leaves.
constexpr double kHingeTolerance = 1e-3;
constexpr double kSlideTolerance = 5e-4;
// Bisection steps of the certificate below the probe's limit once a slab fails.
constexpr int kCertifySteps = 2;
// The thin slab's budget: the slab budget over this.
constexpr long kThinSlabDivisor = 8;
// A slab's leaf budget: the safety stage's per-test budget over this.
constexpr long kSlabBudgetDivisor = 2;
// Free-range ends are found to this [rad or m].
constexpr double kFreeRangeTolerance = 1e-4;

std::vector<std::string> split_names(const std::string& text) {
  std::vector<std::string> names;
  std::stringstream in(text);
  std::string name;
  while (std::getline(in, name, ',')) names.push_back(name);
  return names;
}

// One waypoint's growth: the certifier of this thread, the bounds (its neighbours are read only).
class WaypointGrowth {
 public:
  WaypointGrowth(const Certifier& certifier, CertifyContext& ctx, long leaf_limit,
                 std::vector<WaypointBounds>& bounds, size_t k, long slab_leaves, CertifyStats& stats)
      : certifier_(certifier),
        ctx_(ctx),
        leaf_limit_(leaf_limit),
        b_(bounds),
        k_(k),
        slab_leaves_(slab_leaves),
        stats_(stats) {
    if (k > 0) segments_.push_back({k - 1, k});
    if (k + 1 < bounds.size()) segments_.push_back({k, k + 1});
    if (bounds.size() == 1) segments_.push_back({0, 0});
  }

  // Widens one side of joint i toward `target` (an extent from the nominal value); true when it
  // stopped short (the probe or the certificate said no), so later rounds need not try again.
  bool grow(int i, int side, double target, double tolerance) {
    const double extent = current(i, side);
    if (!(target > extent + tolerance)) return false;
    double candidate = target;
    bool limited = false;
    if (!probe(i, side, target)) {
      double ok = extent, bad = target;
      while (bad - ok > tolerance) {
        const double mid = (ok + bad) / 2;
        (probe(i, side, mid) ? ok : bad) = mid;
      }
      candidate = ok - 2 * tolerance;
      limited = true;
      if (!(candidate > extent + tolerance)) return true;
    }
    // A thin slab first, on a small budget: when it cannot be proven, the thicker ones cannot
    // either, almost always, and a failing slab costs its whole budget.
    const double thin = extent + (candidate - extent) / 8;
    if (!slab_free(i, side, thin, slab_leaves_ / kThinSlabDivisor)) return true;
    set(i, side, thin);
    if (slab_free(i, side, candidate, slab_leaves_)) {
      set(i, side, candidate);
      return limited;
    }
    double ok = thin, bad = candidate;
    for (int step = 0; step < kCertifySteps; ++step) {
      const double mid = (ok + bad) / 2;
      if (slab_free(i, side, mid, slab_leaves_ / 2)) {
        set(i, side, mid);
        ok = mid;
      } else {
        bad = mid;
      }
    }
    return true;
  }

  double current(int i, int side) const {
    const WaypointBounds& w = b_[k_];
    return side ? w.upper[i] - w.q[i] : w.q[i] - w.lower[i];
  }
  void set(int i, int side, double extent) {
    WaypointBounds& w = b_[k_];
    (side ? w.upper[i] : w.lower[i]) = side ? w.q[i] + extent : w.q[i] - extent;
  }

 private:
  // The probe (Certifier::segment_probe) of every segment at this waypoint with the extent set.
  bool probe(int i, int side, double extent) {
    double& bound = side ? b_[k_].upper[i] : b_[k_].lower[i];
    const double kept = bound;  // restored exactly: q -+ (q -+ bound) may differ from it in the last bit
    set(i, side, extent);
    bool free = true;
    for (const auto& [p, r] : segments_) {
      free = certifier_.segment_probe(ctx_, b_[p].lower, b_[p].upper, b_[r].lower, b_[r].upper, b_[p].q,
                                      b_[r].q, kProbeSamples, stats_, nullptr, leaf_limit_);
      if (!free) break;
    }
    bound = kept;
    return free;
  }

  // Widening the extent from the current bound to `to` adds to each certified segment at this
  // waypoint the configurations whose joint i lies between the old and the new bound: at each t a
  // box, linear in t, of zero width at the segment's other end. Only the pairs joint i moves need a
  // proof there (Certifier::segment_free's grown_joint). The old bounds are taken as they are, to
  // the last bit, and the new one is what set() writes.
  bool slab_free(int i, int side, double to, long leaves) {
    const CertifyBudget slab{std::max(64L, leaves), leaf_limit_};
    bool free = true;
    for (const auto& [p, r] : segments_) {
      Eigen::VectorXd lo[2] = {b_[p].lower, b_[r].lower}, hi[2] = {b_[p].upper, b_[r].upper};
      for (int end = 0; end < 2; ++end) {
        const WaypointBounds& w = b_[end ? r : p];
        const double old_bound = side ? w.upper[i] : w.lower[i];
        const double new_bound = (end ? r : p) != k_ ? old_bound : side ? w.q[i] + to : w.q[i] - to;
        lo[end][i] = side ? old_bound : new_bound;
        hi[end][i] = side ? new_bound : old_bound;
      }
      free = certifier_.segment_free(ctx_, lo[0], hi[0], lo[1], hi[1], slab, stats_, nullptr, nullptr, i);
      if (!free) break;
    }
    return free;
  }

  const Certifier& certifier_;
  CertifyContext& ctx_;
  const long leaf_limit_;  // this waypoint's leaf budget, across all its calls
  std::vector<WaypointBounds>& b_;
  size_t k_;
  long slab_leaves_;
  CertifyStats& stats_;
  std::vector<std::pair<size_t, size_t>> segments_;
};

// One waypoint's targets, each side's extent to the end of the joint's one-joint free range
// (capped), and the order in which its joints grow. Greedy: tip to base (the guide leaves the wrist
// least of its room). Lever: by the cost of the joint's kept share, cheapest first (ties tip to
// base). A share s of joint i's free range F_i moves the tool by about s F_i |J_i| (J_i the tool
// site's Jacobian column at the nominal value, linear part), and every step's certificate must
// cover what the step sweeps: maximising the sum of the shares under a bound on that motion is a
// fractional knapsack, whose optimum fills the joints in increasing order of F_i |J_i|.
struct WaypointTargets {
  Eigen::VectorXd below, above;
  std::vector<int> order;
};

WaypointTargets waypoint_targets(RobotState& state, const Eigen::VectorXd& q, const Eigen::VectorXd& caps,
                                 bool lever) {
  const int n = static_cast<int>(q.size());
  const auto free = one_joint_free_ranges(state, q, kFreeRangeTolerance);
  WaypointTargets t;
  t.below.resize(n);
  t.above.resize(n);
  for (int i = 0; i < n; ++i) {
    t.below[i] = std::min(caps[i], q[i] - free[static_cast<size_t>(i)].lower);
    t.above[i] = std::min(caps[i], free[static_cast<size_t>(i)].upper - q[i]);
  }
  for (int i = n - 1; i >= 0; --i) t.order.push_back(i);
  if (!lever) return t;
  state.set(q);
  const Eigen::MatrixXd jacobian = state.tool_jacobian();
  std::vector<double> cost(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    const FreeRange& f = free[static_cast<size_t>(i)];
    cost[static_cast<size_t>(i)] = (f.upper - f.lower) * jacobian.col(i).head<3>().norm();
  }
  std::stable_sort(t.order.begin(), t.order.end(),
                   [&](int a, int b) { return cost[static_cast<size_t>(a)] < cost[static_cast<size_t>(b)]; });
  return t;
}

}  // namespace

std::vector<bool> grow_mask(const Scene& scene, const SafetyParams& params) {
  const auto names = scene.joint_names();
  if (params.grow == "all") return std::vector<bool>(names.size(), true);
  std::vector<bool> mask(names.size(), false);
  if (params.grow == "none") return mask;
  for (const std::string& name : split_names(params.grow)) {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end())
      throw InputError(scene.source() + ": parameter 'safety.grow' = '" + params.grow + "' names joint '" +
                       name +
                       "', which the robot does not have (give all, none or joint names separated "
                       "by commas)");
    mask[static_cast<size_t>(it - names.begin())] = true;
  }
  return mask;
}

Eigen::VectorXd half_width_caps(const Scene& scene, const SafetyParams& params) {
  const auto names = scene.joint_names();
  Eigen::VectorXd caps = Eigen::VectorXd::Constant(scene.dof(), INFINITY);
  for (const auto& [name, half] : params.max_half_width) {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end())
      throw InputError(scene.source() + ": parameter 'safety.max_half_width' names joint '" + name +
                       "', which the robot does not have");
    caps[it - names.begin()] = half;
  }
  return caps;
}

GrowReport grow_bounds(const Scene& scene, std::vector<WaypointBounds>& bounds,
                       const std::vector<SegmentSafety>& segments, const SafetyParams& params,
                       const CertifyOptions& options, int threads) {
  const auto t0 = std::chrono::steady_clock::now();
  GrowReport report;
  const std::vector<bool> mask = grow_mask(scene, params);
  const Eigen::VectorXd caps = half_width_caps(scene, params);
  const int n = scene.dof();
  const size_t count = bounds.size();
  // A cap narrows what the guide gave too (a subset of a certified region is certified).
  for (auto& w : bounds)
    for (int i = 0; i < n; ++i) {
      w.lower[i] = std::max(w.lower[i], w.q[i] - caps[i]);
      w.upper[i] = std::min(w.upper[i], w.q[i] + caps[i]);
    }
  if (std::none_of(mask.begin(), mask.end(), [](bool b) { return b; })) return report;
  report.ran = true;
  // Only a waypoint whose every segment is certified grows (the slabs rely on it).
  std::vector<bool> grows(count, false);
  for (size_t k = 0; k < count; ++k) {
    const bool before = k == 0 || segments[k - 1].passed;
    const bool after = k + 1 >= count || segments[k].passed;
    grows[k] = count == 1 ? segments[0].passed : before && after;
  }
  const bool lever = params.shape == "lever";
  std::vector<WaypointTargets> targets(count);
  detail::parallel_for(static_cast<int>(count), threads, [&] {
    auto state = std::make_shared<RobotState>(scene);
    return [&, state](int k) {
      targets[static_cast<size_t>(k)] =
          waypoint_targets(*state, bounds[static_cast<size_t>(k)].q, caps, lever);
    };
  });
  // blocked[k][2 i + side]: that side stopped short in an earlier round.
  std::vector<std::vector<char>> blocked(count, std::vector<char>(static_cast<size_t>(2 * n), 0));
  std::vector<CertifyStats> stats(count);
  const long slab_leaves = params.max_leaves / kSlabBudgetDivisor;
  const Certifier certifier(scene, options);
  // Each waypoint may spend on growing as many leaves as its segments took to certify (half of each:
  // a segment has two ends), so growth about doubles the certified mode's work at most.
  // A floor of safety.max_leaves, so that a path certified at once can still grow.
  std::vector<long> budget(count, static_cast<long>(params.max_leaves));
  for (size_t s = 0; s < segments.size(); ++s) {
    const long half = segments[s].leaves / 2;
    budget[s] += count == 1 ? segments[s].leaves : half;
    if (s + 1 < count) budget[s + 1] += half;
  }
  // A waypoint's slabs read its neighbours' bounds: even waypoints grow in parallel, then odd ones.
  for (double fraction : lever ? kLeverFractions : kRoundFractions)
    for (size_t parity = 0; parity < 2; ++parity) {
      std::vector<size_t> jobs;
      for (size_t k = parity; k < count; k += 2)
        if (grows[k]) jobs.push_back(k);
      detail::parallel_for(static_cast<int>(jobs.size()), threads, [&] {
        auto ctx = std::make_shared<CertifyContext>(scene);
        return [&, ctx](int job) {
          const size_t k = jobs[static_cast<size_t>(job)];
          WaypointGrowth growth(certifier, *ctx, std::max(1L, budget[k]), bounds, k, slab_leaves, stats[k]);
          const WaypointTargets& target = targets[k];
          for (int i : target.order) {
            if (!mask[static_cast<size_t>(i)]) continue;
            const double tolerance =
                scene.joints()[static_cast<size_t>(i)].prismatic ? kSlideTolerance : kHingeTolerance;
            for (int side = 0; side < 2; ++side) {
              char& stopped = blocked[k][static_cast<size_t>(2 * i + side)];
              if (stopped) continue;
              const double aim = fraction * (side ? target.above[i] : target.below[i]);
              if (growth.grow(i, side, aim, tolerance)) stopped = 1;
            }
          }
        };
      });
    }
  for (size_t k = 0; k < count; ++k) {
    report.stats.add(stats[k]);
    for (int i = 0; i < n; ++i)
      if (bounds[k].lower[i] < bounds[k].guide_lower[i] || bounds[k].upper[i] > bounds[k].guide_upper[i])
        ++report.grown;
  }
  report.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

}  // namespace leeway
