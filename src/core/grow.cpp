#include "grow.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
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
// The one proof that turns a last hinge straight to its target gets the slab budget times this,
// on a budget of its own (not the waypoint's: a failure leaves the rounds what they had).
constexpr long kTurnBudgetFactor = 4;
// Where a last hinge cannot turn with the box it has, the wrist hinges before it keep this share of
// their extents at that waypoint and the turn is tried once more (docs/algorithm.md, "Growing beyond
// the guide", step 3): a quarter kept the most room on the 15 sparse paths (CHANGELOG.md).
constexpr double kWristKept = 0.25;
// The turn's quick test looks at the slab's corners at this many points along each segment.
constexpr int kTurnCornerSteps = 16;
// ... and at the corners of at most this many moving joints (the others keep their intervals).
constexpr int kTurnCornerJoints = 8;
// Free-range ends are found to this [rad or m].
constexpr double kFreeRangeTolerance = 1e-4;

std::vector<std::string> split_names(const std::string& text) {
  std::vector<std::string> names;
  std::stringstream in(text);
  std::string name;
  while (std::getline(in, name, ',')) names.push_back(name);
  return names;
}

// The probe's limit between an extent it accepts (`ok`) and one it refuses (`bad`), found by
// bisection to `tolerance`, less twice the tolerance: the margin's last millimetre costs the
// certificate most of its leaves.
template <class Probe>
double probe_limit(double ok, double bad, double tolerance, Probe probe) {
  while (bad - ok > tolerance) {
    const double mid = (ok + bad) / 2;
    (probe(mid) ? ok : bad) = mid;
  }
  return ok - 2 * tolerance;
}

// The bound of a joint on `side` (1: upper) at `extent` from its nominal value q, within the joint's
// limits: q + (limit - q) may pass the limit by a rounding error, and a bounds file whose interval
// leaves the limits is refused.
double limited_bound(const RobotJoint& joint, double q, int side, double extent) {
  return side ? std::min(joint.upper, q + extent) : std::max(joint.lower, q - extent);
}

// The certificate's part of one growth step from `extent` to the probe's `candidate`, for a
// waypoint or a block: a thin slab first, on a small budget (when it cannot be proven, the thicker
// ones cannot either, almost always, and a failing slab costs its whole budget), then the whole
// step, then kCertifySteps bisection steps. slab_free(to, leaves) proves the slab from the current
// extent to `to`; set(to) keeps it. True when the step stopped short of the candidate, or `limited`
// (the probe stopped it short of its target).
template <class SlabFree, class Set>
bool certify_step(double extent, double candidate, bool limited, long slab_leaves, SlabFree slab_free,
                  Set set) {
  const double thin = extent + (candidate - extent) / 8;
  if (!slab_free(thin, slab_leaves / kThinSlabDivisor)) return true;
  set(thin);
  if (slab_free(candidate, slab_leaves)) {
    set(candidate);
    return limited;
  }
  double proven = thin, refused = candidate;
  for (int step = 0; step < kCertifySteps; ++step) {
    const double mid = (proven + refused) / 2;
    if (slab_free(mid, slab_leaves / 2)) {
      set(mid);
      proven = mid;
    } else {
      refused = mid;
    }
  }
  return true;
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
    bool limited = false;
    const double candidate = step_end(i, side, target, tolerance, limited);
    if (!(candidate > extent + tolerance)) return limited;
    return certify_step(
        extent, candidate, limited, slab_leaves_,
        [&](double to, long leaves) { return slab_free(i, side, to, leaves); },
        [&](double to) { set(i, side, to); });
  }

  // Where a turn of one side of joint i toward `target` ends: the target, or the probe's limit
  // short of it (step_end).
  double turn_end(int i, int side, double target, double tolerance) {
    bool limited = false;
    return step_end(i, side, target, tolerance, limited);
  }

  // Widens one side of joint i straight to `to` (a turn_end) in one proof of `leaves`: for a joint
  // that turns last (Certifier::turns_last) the pivot cylinder proves a wide slab for the price of a
  // thin one, where the geoms' own bounds would need the joint split finely. Nothing changes when
  // the proof fails. False when it failed (true when the side had no step to take).
  bool turn_to(int i, int side, double to, double tolerance, long leaves) {
    if (!(to > current(i, side) + tolerance)) return true;
    if (!slab_free(i, side, to, leaves)) return false;
    set(i, side, to);
    return true;
  }

  // A quick test, not a proof, of the slab that turn_to(i, side, to) would prove: one leaf at each
  // corner of the slab's box (joint i over the whole slab, the other joints at their bounds) at
  // kTurnCornerSteps points along each segment. False when a leaf is not proven: the pivot cylinder
  // does not hold the geoms there, and the proof could only split joint i finely, which costs a
  // wide turn most of its budget (measured on the 15 sparse paths: CHANGELOG.md).
  bool turn_corners_free(int i, int side, double to, double tolerance) {
    if (!(to > current(i, side) + tolerance)) return true;
    for (const auto& [p, r] : segments_) {
      Eigen::VectorXd lo[2], hi[2];
      slab_ends(i, side, to, p, r, lo, hi);
      for (int step = 0; step < kTurnCornerSteps; ++step) {
        // From this waypoint's end, where the slab is widest, toward the other end.
        const double f = static_cast<double>(step) / kTurnCornerSteps;
        const double t = p == k_ ? f : 1 - f;
        const Eigen::VectorXd l = (1 - t) * lo[0] + t * lo[1], h = (1 - t) * hi[0] + t * hi[1];
        std::vector<int> moving;
        for (int j = 0; j < static_cast<int>(l.size()); ++j)
          if (j != i && h[j] > l[j] && static_cast<int>(moving.size()) < kTurnCornerJoints)
            moving.push_back(j);
        Eigen::VectorXd cl = l, ch = h;
        for (unsigned corner = 0; corner < (1u << moving.size()); ++corner) {
          for (size_t b = 0; b < moving.size(); ++b)
            cl[moving[b]] = ch[moving[b]] = (corner >> b) & 1u ? h[moving[b]] : l[moving[b]];
          if (!certifier_.leaf_free(ctx_, cl, ch, stats_)) return false;
        }
      }
    }
    return true;
  }

  double current(int i, int side) const {
    const WaypointBounds& w = b_[k_];
    return side ? w.upper[i] - w.q[i] : w.q[i] - w.lower[i];
  }
  void set(int i, int side, double extent) {
    (side ? b_[k_].upper[i] : b_[k_].lower[i]) = bound(i, side, extent);
  }

 private:
  // Where a step of one side of joint i toward `target` ends: the target when the probe accepts it,
  // else the probe's limit short of it (`limited` set); the current extent when the target is
  // within `tolerance` of it.
  double step_end(int i, int side, double target, double tolerance, bool& limited) {
    limited = false;
    const double extent = current(i, side);
    if (!(target > extent + tolerance) || probe(i, side, target)) return std::max(extent, target);
    limited = true;
    return probe_limit(extent, target, tolerance, [&](double to) { return probe(i, side, to); });
  }

  // The probe (Certifier::segment_probe) of every segment at this waypoint with the extent set. Only
  // the pairs joint i moves: a configuration the step adds is one of the certified region with joint
  // i moved (the other pairs' geometry does not change), so they are apart there as well.
  bool probe(int i, int side, double extent) {
    double& bound = side ? b_[k_].upper[i] : b_[k_].lower[i];
    const double kept = bound;  // restored exactly: q -+ (q -+ bound) may differ from it in the last bit
    set(i, side, extent);
    bool free = true;
    for (const auto& [p, r] : segments_) {
      free = certifier_.segment_probe(ctx_, b_[p].lower, b_[p].upper, b_[r].lower, b_[r].upper, b_[p].q,
                                      b_[r].q, kProbeSamples, stats_, nullptr, leaf_limit_, i);
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
    // A stretch that fails is not cut into shorter ones: growth's slabs go further for the same
    // leaves when each stretch's joint splits get the whole budget (docs/algorithm.md, "Growing beyond the
    // guide", step 5).
    const CertifyBudget slab{std::max(64L, leaves), leaf_limit_, false};
    bool free = true;
    for (const auto& [p, r] : segments_) {
      Eigen::VectorXd lo[2], hi[2];
      slab_ends(i, side, to, p, r, lo, hi);
      free = certifier_.segment_free(ctx_, lo[0], hi[0], lo[1], hi[1], slab, stats_, nullptr, nullptr, i);
      if (!free) break;
    }
    return free;
  }

  // The slab's bounds at the ends of segment (p, r): the segment's own, with joint i between the
  // old bound and the new one at this waypoint (`to` from the nominal value), at the old bound at
  // the other end.
  void slab_ends(int i, int side, double to, size_t p, size_t r, Eigen::VectorXd lo[2],
                 Eigen::VectorXd hi[2]) const {
    for (int end = 0; end < 2; ++end) {
      const WaypointBounds& w = b_[end ? r : p];
      lo[end] = w.lower;
      hi[end] = w.upper;
      const double old_bound = side ? w.upper[i] : w.lower[i];
      const double new_bound = (end ? r : p) != k_ ? old_bound : bound(i, side, to);
      lo[end][i] = side ? old_bound : new_bound;
      hi[end][i] = side ? new_bound : old_bound;
    }
  }

  // This waypoint's bound of joint i on `side` at `extent` from the nominal value.
  double bound(int i, int side, double extent) const {
    return limited_bound(certifier_.scene().joints()[static_cast<size_t>(i)], b_[k_].q[i], side, extent);
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

// A dense path grows by blocks of this many segments: one box (the hull of the block's waypoint
// boxes, which holds each of its segments' regions) is proven free, then grown one joint side at a
// time by box slabs, and every waypoint of the block takes the same extent.
constexpr size_t kBlockSegments = 16;
// The block's hull proof gets the leaf budget over this (as a run box does), its slabs a
// waypoint's slab budget over kBlockSlabDivisor, so that a dense path's growth stays a small part
// of its certificate's cost (docs/results.md, "Scale").
constexpr long kHullBudgetDivisor = 4;
constexpr long kBlockSlabDivisor = 4;
// A block's probe walks outward from its extent in steps of this many tolerances, doubling.
constexpr double kMarchSteps = 16;

// One block's growth on a dense path. Waypoints first..last; `fix_first`, `fix_last`: that end
// waypoint (shared with a neighbouring block that grew first) keeps its bounds.
class BlockGrowth {
 public:
  BlockGrowth(const Certifier& certifier, CertifyContext& ctx, std::vector<WaypointBounds>& bounds,
              size_t first, size_t last, bool fix_first, bool fix_last, long max_leaves, CertifyStats& stats)
      : certifier_(certifier),
        ctx_(ctx),
        b_(bounds),
        grow_first_(fix_first ? first + 1 : first),
        grow_last_(fix_last ? last - 1 : last),
        hull_leaves_(std::max(64L, max_leaves / kHullBudgetDivisor)),
        slab_leaves_(max_leaves / kSlabBudgetDivisor / kBlockSlabDivisor),
        stats_(stats) {
    lo_ = b_[first].lower;
    hi_ = b_[first].upper;
    for (size_t k = first + 1; k <= last; ++k) {
      lo_ = lo_.cwiseMin(b_[k].lower);
      hi_ = hi_.cwiseMax(b_[k].upper);
    }
  }

  // Proves the hull free (every later slab relies on it).
  bool hull_free() {
    const CertifyBudget budget{hull_leaves_};
    return certifier_.region_free(ctx_, lo_, hi_, budget, stats_);
  }

  // The smallest extent of joint i on `side` over the waypoints that grow (infinite when none do).
  double current(int i, int side) const {
    double e = INFINITY;
    for (size_t k = grow_first_; k <= grow_last_; ++k)
      e = std::min(e, side ? b_[k].upper[i] - b_[k].q[i] : b_[k].q[i] - b_[k].lower[i]);
    return e;
  }
  // Per joint, the largest extent on `side` that takes some growing waypoint to the joint's limit.
  Eigen::VectorXd to_limits(int side) const {
    const Scene& scene = certifier_.scene();
    Eigen::VectorXd extent = Eigen::VectorXd::Zero(scene.dof());
    for (size_t k = grow_first_; k <= grow_last_; ++k)
      extent = extent.cwiseMax(side ? scene.upper_limits() - b_[k].q : b_[k].q - scene.lower_limits());
    return extent;
  }

  // Widens joint i on `side` toward extent `target` at every growing waypoint of the block; true
  // when it stopped short.
  bool grow(int i, int side, double target, double tolerance) {
    const double extent = current(i, side);
    if (!(target > extent + tolerance)) return false;
    // Outward in doubling steps, then bisection between the last free face and the first one that
    // is not: the target is the joint's limit, whose face may be free beyond an obstacle the slab
    // crosses.
    double ok = extent, bad = target;
    bool limited = false;
    for (double step = kMarchSteps * tolerance; ok < target; step *= 2) {
      const double next = std::min(target, ok + step);
      if (!face_free(i, side, next)) {
        bad = next;
        limited = true;
        break;
      }
      ok = next;
    }
    double candidate = target;
    if (limited) {
      candidate = probe_limit(ok, bad, tolerance, [&](double to) { return face_free(i, side, to); });
      if (!(candidate > extent + tolerance)) return true;
    }
    return certify_step(
        extent, candidate, limited, slab_leaves_,
        [&](double to, long leaves) { return slab_free(i, side, to, leaves); },
        [&](double to) { set(i, side, to); });
  }

 private:
  // The hull's edge of joint i on `side` with every growing waypoint at least `extent` wide there.
  double edge(int i, int side, double extent) const {
    double edge = side ? hi_[i] : lo_[i];
    for (size_t k = grow_first_; k <= grow_last_; ++k)
      edge = side ? std::max(edge, widened(k, i, side, extent)) : std::min(edge, widened(k, i, side, extent));
    return edge;
  }

  // Waypoint k's bound of joint i on `side` widened to `extent`, within the joint's limits.
  double widened(size_t k, int i, int side, double extent) const {
    const WaypointBounds& w = b_[k];
    const double to =
        limited_bound(certifier_.scene().joints()[static_cast<size_t>(i)], w.q[i], side, extent);
    return side ? std::max(w.upper[i], to) : std::min(w.lower[i], to);
  }

  // The slab the growth adds to the hull, joint i from the hull's edge to the new one.
  std::pair<Eigen::VectorXd, Eigen::VectorXd> slab(int i, int side, double extent) const {
    Eigen::VectorXd lo = lo_, hi = hi_;
    const double to = edge(i, side, extent);
    if (side) {
      lo[i] = hi_[i];
      hi[i] = to;
    } else {
      hi[i] = lo_[i];
      lo[i] = to;
    }
    return {lo, hi};
  }

  // The probe: the slab's outer face (joint i at the new edge), its corners and centre, only the
  // pairs joint i moves. A slab that comes too close does so at its outer face first, in most cases.
  bool face_free(int i, int side, double extent) const {
    auto [lo, hi] = slab(i, side, extent);
    (side ? lo[i] : hi[i]) = side ? hi[i] : lo[i];
    return certifier_.box_probe(ctx_, lo, hi, stats_, std::numeric_limits<long>::max(), i);
  }

  bool slab_free(int i, int side, double extent, long leaves) const {
    const auto [lo, hi] = slab(i, side, extent);
    if (!(hi[i] > lo[i])) return true;  // the hull holds it already
    const CertifyBudget budget{std::max(64L, leaves)};
    return certifier_.segment_free(ctx_, lo, hi, lo, hi, budget, stats_, nullptr, nullptr, i);
  }

  void set(int i, int side, double extent) {
    const double to = edge(i, side, extent);
    (side ? hi_[i] : lo_[i]) = to;
    for (size_t k = grow_first_; k <= grow_last_; ++k)
      (side ? b_[k].upper[i] : b_[k].lower[i]) = widened(k, i, side, extent);
  }

  const Certifier& certifier_;
  CertifyContext& ctx_;
  std::vector<WaypointBounds>& b_;
  // The waypoints that grow (none in a one-segment block whose ends are fixed).
  const size_t grow_first_, grow_last_;
  const long hull_leaves_, slab_leaves_;
  CertifyStats& stats_;
  Eigen::VectorXd lo_, hi_;  // the hull, proven free once hull_free() said so
};

// The growth of one block of a dense path. A block's fixed ends were grown by the even blocks
// beside it: when the block cannot grow (a segment not certified, or its hull not proven), they go
// back to their bounds from before any growth, a subset of what those blocks proved and what this
// block's segments were certified with.
struct DenseBlock {
  const Certifier& certifier;
  CertifyContext& ctx;
  std::vector<WaypointBounds>& bounds;
  const std::vector<WaypointBounds>& before;
  const std::vector<SegmentSafety>& segments;
  const std::vector<bool>& mask;
  const Eigen::VectorXd& caps;
  long max_leaves;
  CertifyStats& stats;

  void grow(size_t first, size_t last, bool fix_first, bool fix_last) {
    bool certified = true;
    for (size_t s = first; s < last; ++s) certified = certified && segments[s].passed;
    if (certified) {
      BlockGrowth growth(certifier, ctx, bounds, first, last, fix_first, fix_last, max_leaves, stats);
      if (growth.hull_free()) {
        widen(growth);
        return;
      }
    }
    if (fix_first) bounds[first] = before[first];
    if (fix_last) bounds[last] = before[last];
  }

  // One pass, tip to base, each side straight toward its joint limits (or caps): the face probe's
  // walk and bisection find where the block's slab first comes within the margin. (A block's box
  // meets an obstacle before the one-joint free range ends, and that range, computed at every
  // block, cost about as much as the growth it aimed: docs/algorithm.md, "Growing".)
  void widen(BlockGrowth& growth) const {
    const Scene& scene = certifier.scene();
    const Eigen::VectorXd below = growth.to_limits(0).cwiseMin(caps),
                          above = growth.to_limits(1).cwiseMin(caps);
    for (int i = scene.dof() - 1; i >= 0; --i) {
      if (!mask[static_cast<size_t>(i)]) continue;
      const double tolerance =
          scene.joints()[static_cast<size_t>(i)].prismatic ? kSlideTolerance : kHingeTolerance;
      for (int side = 0; side < 2; ++side) growth.grow(i, side, side ? above[i] : below[i], tolerance);
    }
  }
};

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

namespace {

// Every interval capped (a cap narrows what the guide gave too: a subset of a certified region is
// certified); the caps, for growth not to pass them either.
Eigen::VectorXd cap_intervals(const Scene& scene, const SafetyParams& params,
                              std::vector<WaypointBounds>& bounds) {
  const Eigen::VectorXd caps = half_width_caps(scene, params);
  for (auto& w : bounds) {
    w.lower = w.lower.cwiseMax(w.q - caps);
    w.upper = w.upper.cwiseMin(w.q + caps);
  }
  return caps;
}

// The intervals (waypoint x joint) wider than the guide's on some side.
int grown_intervals(const std::vector<WaypointBounds>& bounds) {
  int grown = 0;
  for (const WaypointBounds& w : bounds)
    grown += static_cast<int>(
        ((w.lower.array() < w.guide_lower.array()) || (w.upper.array() > w.guide_upper.array())).count());
  return grown;
}

bool any(const std::vector<bool>& mask) { return std::find(mask.begin(), mask.end(), true) != mask.end(); }

// A leaf budget times safety.grow_leaves, at least one leaf.
long scaled(long leaves, double factor) {
  return std::max(1L, static_cast<long>(std::llround(static_cast<double>(leaves) * factor)));
}

// Calls grow_one(k, ctx) at every waypoint k that grows, with a certificate context of the calling
// thread: even waypoints in parallel, then odd ones (a waypoint's slabs read its neighbours' bounds).
template <class GrowOne>
void each_growing_waypoint(const Scene& scene, const std::vector<bool>& grows, int threads,
                           GrowOne grow_one) {
  for (size_t parity = 0; parity < 2; ++parity) {
    std::vector<size_t> jobs;
    for (size_t k = parity; k < grows.size(); k += 2)
      if (grows[k]) jobs.push_back(k);
    detail::parallel_for(static_cast<int>(jobs.size()), threads, [&] {
      auto ctx = std::make_shared<CertifyContext>(scene);
      return [&, ctx](int job) { grow_one(jobs[static_cast<size_t>(job)], *ctx); };
    });
  }
}

// The wrist of a joint i that turns last: the hinges before it that growth may change (`mask`) and
// that the guide's default rule does not bisect (bound_kinds with default parameters: the arm's first
// three hinges are bisected, and the turn does not narrow them).
std::vector<int> wrist_before(const Scene& scene, const std::vector<bool>& mask, int i) {
  const std::vector<BoundKind> kinds = bound_kinds(scene, BoundsParams{});
  std::vector<int> wrist;
  for (int j = 0; j < i; ++j)
    if (kinds[static_cast<size_t>(j)] == BoundKind::kFixed && mask[static_cast<size_t>(j)])
      wrist.push_back(j);
  return wrist;
}

// Before the rounds: every joint i that turns last (Certifier::turns_last) is widened at each
// growing waypoint straight to its targets (WaypointGrowth::turn), even waypoints in parallel, then
// odd ones. One proof per side, the upper side only when the lower one was proven (the pivot
// cylinder that proves one side proves the other: when one runs out of leaves, the other almost
// always does too). Where i has a wrist (wrist_before) and the quick corner test or the lower side
// fails, the wrist keeps kWristKept of its extents at that waypoint and the turn is tried once
// more; when that fails as well, the waypoint's bounds are restored. Leaves go to `stats`, apart
// from the waypoints' growth budgets.
void turn_last_hinges(const Scene& scene, const Certifier& certifier, std::vector<WaypointBounds>& bounds,
                      const std::vector<bool>& grows, const std::vector<bool>& mask,
                      const std::vector<WaypointTargets>& targets, long slab_leaves, int threads,
                      std::vector<CertifyStats>& stats) {
  const long leaves = kTurnBudgetFactor * slab_leaves;
  for (int i = 0; i < scene.dof(); ++i) {
    if (!mask[static_cast<size_t>(i)] || scene.joints()[static_cast<size_t>(i)].prismatic ||
        !certifier.turns_last(i))
      continue;
    const std::vector<int> wrist = wrist_before(scene, mask, i);
    each_growing_waypoint(scene, grows, threads, [&](size_t k, CertifyContext& ctx) {
      // Two tries of two sides and the corner tests.
      WaypointGrowth growth(certifier, ctx, 5 * leaves, bounds, k, 0, stats[k]);
      const WaypointTargets& target = targets[k];
      // The lower side's end, with the bounds as they are when it is called (the probe's limit
      // depends on the other joints' intervals).
      auto lower_end = [&] { return growth.turn_end(i, 0, target.below[i], kHingeTolerance); };
      auto turn_both = [&](double below) {
        if (!growth.turn_to(i, 0, below, kHingeTolerance, leaves)) return false;
        growth.turn_to(i, 1, growth.turn_end(i, 1, target.above[i], kHingeTolerance), kHingeTolerance,
                       leaves);
        return true;
      };
      if (wrist.empty()) {
        turn_both(lower_end());
        return;
      }
      const double below = lower_end();
      if (growth.turn_corners_free(i, 0, below, kHingeTolerance) && turn_both(below)) return;
      WaypointBounds& w = bounds[k];
      const WaypointBounds kept = w;
      for (int j : wrist) {
        w.lower[j] = w.q[j] - kWristKept * (w.q[j] - w.lower[j]);
        w.upper[j] = w.q[j] + kWristKept * (w.upper[j] - w.q[j]);
      }
      if (!turn_both(lower_end())) w = kept;
    });
  }
}

}  // namespace

GrowReport grow_bounds(const Scene& scene, std::vector<WaypointBounds>& bounds,
                       const std::vector<SegmentSafety>& segments, const SafetyParams& params,
                       const CertifyOptions& options, int threads) {
  const auto t0 = std::chrono::steady_clock::now();
  GrowReport report;
  const std::vector<bool> mask = grow_mask(scene, params);
  const Eigen::VectorXd caps = cap_intervals(scene, params, bounds);
  const int n = scene.dof();
  const size_t count = bounds.size();
  if (!any(mask)) return report;
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
      if (grows[static_cast<size_t>(k)])
        targets[static_cast<size_t>(k)] =
            waypoint_targets(*state, bounds[static_cast<size_t>(k)].q, caps, lever);
    };
  });
  // blocked[k][2 i + side]: that side stopped short in an earlier round.
  std::vector<std::vector<char>> blocked(count, std::vector<char>(static_cast<size_t>(2 * n), 0));
  std::vector<CertifyStats> stats(count);
  const long slab_leaves = scaled(params.max_leaves / kSlabBudgetDivisor, params.grow_leaves);
  const Certifier certifier(scene, options);
  // Each waypoint may spend on growing as many leaves as its segments took to certify (half of each:
  // a segment has two ends), so growth about doubles the certified mode's work at most.
  // A floor of safety.max_leaves, so that a path certified at once can still grow.
  // safety.grow_leaves scales both.
  std::vector<long> budget(count, static_cast<long>(params.max_leaves));
  for (size_t s = 0; s < segments.size(); ++s) {
    const long half = segments[s].leaves / 2;
    budget[s] += count == 1 ? segments[s].leaves : half;
    if (s + 1 < count) budget[s + 1] += half;
  }
  for (long& b : budget) b = scaled(b, params.grow_leaves);
  std::vector<CertifyStats> turn_stats(count);
  if (params.turn)
    turn_last_hinges(scene, certifier, bounds, grows, mask, targets, slab_leaves, threads, turn_stats);
  for (double fraction : lever ? kLeverFractions : kRoundFractions)
    each_growing_waypoint(scene, grows, threads, [&](size_t k, CertifyContext& ctx) {
      WaypointGrowth growth(certifier, ctx, std::max(1L, budget[k]), bounds, k, slab_leaves, stats[k]);
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
    });
  for (const CertifyStats& st : turn_stats) report.stats.add(st);
  for (const CertifyStats& st : stats) report.stats.add(st);
  report.grown = grown_intervals(bounds);
  report.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

GrowReport grow_dense(const Scene& scene, std::vector<WaypointBounds>& bounds,
                      const std::vector<SegmentSafety>& segments, const SafetyParams& params,
                      const CertifyOptions& options, int threads) {
  const auto t0 = std::chrono::steady_clock::now();
  GrowReport report;
  const std::vector<bool> mask = grow_mask(scene, params);
  const Eigen::VectorXd caps = cap_intervals(scene, params, bounds);
  const size_t count = bounds.size();
  if (count < 2 || !any(mask)) return report;
  report.ran = true;
  const size_t blocks = (count - 2) / kBlockSegments + 1;
  std::vector<CertifyStats> stats(blocks);
  const Certifier certifier(scene, options);
  // Even blocks first, in parallel; then odd ones, whose two end waypoints the even ones grew.
  const std::vector<WaypointBounds> before = bounds;
  for (size_t parity = 0; parity < 2; ++parity) {
    std::vector<size_t> jobs;
    for (size_t g = parity; g < blocks; g += 2) jobs.push_back(g);
    detail::parallel_for(static_cast<int>(jobs.size()), threads, [&] {
      auto ctx = std::make_shared<CertifyContext>(scene);
      return [&, ctx](int job) {
        const size_t g = jobs[static_cast<size_t>(job)];
        const size_t first = g * kBlockSegments, last = std::min(first + kBlockSegments, count - 1);
        // An odd block's ends belong to the even blocks beside it (the path's last waypoint does not).
        DenseBlock block{certifier, *ctx, bounds, before,
                         segments,  mask, caps,   scaled(params.max_leaves, params.grow_leaves),
                         stats[g]};
        block.grow(first, last, parity == 1, parity == 1 && last + 1 < count);
      };
    });
  }
  for (const CertifyStats& st : stats) report.stats.add(st);
  report.grown = grown_intervals(bounds);
  report.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

}  // namespace leeway
