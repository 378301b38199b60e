#include "leeway/core/safety.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <random>

#include "grow.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/shape.hpp"
#include "parallel.hpp"
#include "random.hpp"

namespace leeway {
namespace {

// Extents below this are set to zero: the bound sits on the nominal value [rad or m].
constexpr double kTinyExtent = 1e-6;
// Shrink steps one segment may take before it is reported as not certified.
constexpr int kMaxShrinkSteps = 400;
// Steps that regrow one shrunk extent toward its guide value: bisection against the probe, then
// the certificate (the probe's limit, a thin slab an eighth of the way to it, bisection; on a short
// segment the thin slab comes first).
constexpr int kProbeSteps = 4;
constexpr int kRegrowSteps = 4;
// A slab (what one regrow step adds) gets this fraction of the leaf budget: a slab that needs more
// is not worth its cost. On a short segment (is_short) the first, thin slab is a cheap test of
// whether growing is possible at all, which on dense paths fails in most cases: it gets less.
constexpr long kSlabBudgetDivisor = 4;
constexpr long kThinSlabBudgetDivisor = 16;
// Phases of a dense path's segments (three otherwise): segments this far apart run in parallel,
// the ones between them in order, each starting from its settled neighbour (warm start).
constexpr size_t kDensePhases = 16;
// On a dense path, every this many segments (and where the guide changes between a segment's ends,
// see guide_steady), a warm-started segment regrows its end b toward the guide even when it needed
// no shrinking: warm starts only narrow, and this lets the intervals widen again where the path
// leaves the obstacles, between cold segments.
constexpr size_t kWidenEvery = 4;
// Random configurations a probe checks besides the corners.
constexpr int kProbeSamples = 200;
// A run's box (RunBox) holds the segments up to this many waypoints ahead; its proof gets the leaf
// budget over kRunBudgetDivisor (a failing proof costs all of it), and a chain of segments stops
// trying new run boxes after kMaxRunFailures failed ones.
constexpr size_t kRunWaypoints = 16;
constexpr long kRunBudgetDivisor = 4;
constexpr int kMaxRunFailures = 2;

// The bounds as the nominal value and the extents below and above it, which shrink independently.
struct Extents {
  std::vector<Eigen::VectorXd> q, below, above;
  explicit Extents(const std::vector<WaypointBounds>& b) {
    for (const auto& w : b) {
      q.push_back(w.q);
      below.push_back(w.q - w.lower);
      above.push_back(w.upper - w.q);
    }
  }
  Eigen::VectorXd lower(size_t k) const { return q[k] - below[k]; }
  Eigen::VectorXd upper(size_t k) const { return q[k] + above[k]; }
};

// At every joint, the point `from` (at waypoint a) and `to` (at waypoint b) are at most a twentieth
// of the guide's narrower half-width plus 5 mrad (or mm) apart.
bool moves_little(const Extents& guide, size_t a, size_t b, const Eigen::VectorXd& from,
                  const Eigen::VectorXd& to) {
  for (Eigen::Index i = 0; i < from.size(); ++i) {
    const double half =
        std::min(guide.below[a][i] + guide.above[a][i], guide.below[b][i] + guide.above[b][i]) / 2;
    if (std::abs(to[i] - from[i]) > 0.05 * half + 0.005) return false;
  }
  return true;
}

// A segment of a dense path: the nominal value moves little between its ends (moves_little), so its
// region is about the box at either end, and the boxes at its two ends can be about the same.
bool is_short(const Extents& guide, size_t a, size_t b) {
  return moves_little(guide, a, b, guide.q[a], guide.q[b]);
}

// The guide's intervals at the two ends are about the same: their centres move by as little as
// is_short's nominal values. (The guide of the thesis's bisection can jump between neighbouring
// waypoints of a dense path.)
bool guide_steady(const Extents& guide, size_t a, size_t b) {
  return moves_little(guide, a, b, (guide.lower(a) + guide.upper(a)) / 2,
                      (guide.lower(b) + guide.upper(b)) / 2);
}

void halve(double& extent) { extent = extent / 2 < kTinyExtent ? 0.0 : extent / 2; }

using detail::splitmix;
using detail::unit;

// What the warm segments of one chain on a dense path share (a chain: the segments from one of
// phase 0 to the next, which run one after the other, each warm from the one before; the first,
// cold one starts from the guide, which on dense paths is rarely free). A box proven free that
// holds the boxes of several of its consecutive segments: a segment whose box (the hull of its two ends'
// boxes, which holds its box at every t) lies inside it is certified without a proof of its own.
// And the joint sides whose widening (kWidenEvery) the certificate refused in this chain: its later
// segments do not try them again, since they fail in most cases and each failure costs a thin
// slab's budget.
struct RunBox {
  Eigen::VectorXd lower, upper;
  bool proven = false;
  int failures = 0;
  std::vector<char> refused;  // [2 i + side], sized by make_safe
};

// Which neighbouring segments share the segment's waypoints and ran before it (a regrown waypoint
// must keep them certified), and whether they were certified.
struct Neighbours {
  bool check_previous = false, check_next = false;
  bool previous_certified = false, next_certified = false;
};

// Certified mode for the segment between waypoints a and b (a == b for a one-waypoint path).
// Shrink: while a quick probe (exact checks of corners and samples) finds a configuration too close
// to an obstacle, and then while the certificate fails, halve the extent of the joint blamed for it,
// on its side of the nominal value, at the end(s) of the segment that weigh most at its path
// parameter (then at both ends; when that extent is already zero, every extent). Regrow: every
// shrunk extent is then bisected back toward its guide value, first against the probe (cheap),
// then against the certificate (kRegrowSteps steps, each proving only the slab the growth adds),
// for this segment and for the neighbouring segments that share the regrown waypoint and ran
// before. `guide` holds the extents before the safety stage. A segment that cannot be certified
// keeps only its nominal values. Every call counts its leaves in one CertifyStats, capped by the
// segment's budget (leaf_limit): a call that reaches it fails with f.budget set.
class SegmentRepair {
 public:
  SegmentRepair(const Certifier& certifier, CertifyContext& ctx, long leaf_limit, Extents& e,
                const Extents& guide, size_t a, size_t b, const Neighbours& nb, RunBox* run)
      : certifier_(certifier),
        ctx_(ctx),
        e_(e),
        guide_(guide),
        a_(a),
        b_(b),
        nb_(nb),
        n_(static_cast<int>(e.q[a].size())),
        short_(is_short(guide, a, b)),
        run_(short_ && a != b && nb.check_previous ? run : nullptr) {
    budget_ = certifier.budget();
    budget_.leaf_limit = leaf_limit;
    // A stretch of a long segment that fails is not cut along the path: each shorter stretch
    // would prove the whole box of the joints again, and its joint splits go further with the
    // whole remaining budget. A dense path's short segments still cut: there cutting saves leaves
    // (docs/algorithm.md, "The region to prove free").
    budget_.split_path_on_failure = short_;
  }

  SegmentSafety run(CertifyStats& total) {
    warm_start();
    shrink_until_certified();
    if (s_.passed && (s_.shrink_steps > 0 || widen_b_)) regrow();
    // (A regrow step that ran out kept the extent it had proven: the segment stays certified.)
    if (out_of_budget()) s_.budget_exhausted = true;
    s_.leaves = stats_.leaves;
    s_.max_depth = stats_.max_depth;
    total.add(stats_);
    return s_;
  }

 private:
  bool out_of_budget() const { return stats_.leaves >= budget_.leaf_limit; }
  bool certified(size_t from, size_t to, CertifyFailure* f) {
    return certifier_.segment_free(ctx_, e_.lower(from), e_.upper(from), e_.lower(to), e_.upper(to), budget_,
                                   stats_, f, &proven_);
  }
  bool probed(size_t from, size_t to, CertifyFailure* f) {
    return certifier_.segment_probe(ctx_, e_.lower(from), e_.upper(from), e_.lower(to), e_.upper(to),
                                    e_.q[from], e_.q[to], kProbeSamples, stats_, f, budget_.leaf_limit);
  }

  // Warm start: on a short segment whose end a was settled by the segment before it (an earlier
  // phase), end b starts from end a's intervals where they are narrower than its own (clipped at
  // its nominal value), and those are its regrow targets: a dense path's neighbouring waypoints
  // need about the same intervals, and searching them again from the guide would repeat the
  // failing proofs that settled end a. When end b was settled too (by the segment after it), it
  // is narrowed the same way, and end a's regrow target is its settled value: each end's own
  // search is over. A segment that widens (kWidenEvery) keeps the guide as end b's target.
  void warm_start() {
    const size_t a = a_, b = b_;
    target_below_[0] = guide_.below[a];
    target_above_[0] = guide_.above[a];
    target_below_[1] = guide_.below[b];
    target_above_[1] = guide_.above[b];
    const bool warm = short_ && nb_.check_previous && a != b;
    widen_b_ = warm && !nb_.check_next && (a % kWidenEvery == 0 || !guide_steady(guide_, a, b));
    if (warm && nb_.check_next) {
      target_below_[0] = e_.below[a];
      target_above_[0] = e_.above[a];
    }
    if (!warm) return;
    const Eigen::VectorXd lower_a = e_.lower(a), upper_a = e_.upper(a), lower_b = e_.lower(b),
                          upper_b = e_.upper(b);
    for (int i = 0; i < n_; ++i) {
      // (Beyond rounding only: an untouched bound keeps its exact value.)
      if (lower_a[i] > lower_b[i] + kTinyExtent) e_.below[b][i] = std::max(0.0, e_.q[b][i] - lower_a[i]);
      if (upper_a[i] < upper_b[i] - kTinyExtent) e_.above[b][i] = std::max(0.0, upper_a[i] - e_.q[b][i]);
    }
    if (!widen_b_) {
      target_below_[1] = e_.below[b];
      target_above_[1] = e_.above[b];
    }
  }

  // The box of segment (from, to) at the extents set: the hull of its two ends' boxes, which holds
  // its box at every t.
  std::pair<Eigen::VectorXd, Eigen::VectorXd> segment_box(size_t from, size_t to) const {
    return {e_.lower(from).cwiseMin(e_.lower(to)), e_.upper(from).cwiseMax(e_.upper(to))};
  }

  // Whether the run's box is proven and holds the box of segment (from, to) at the extents set.
  bool run_box_holds(size_t from, size_t to) const {
    if (!run_ || !run_->proven) return false;
    const auto [lower, upper] = segment_box(from, to);
    return (run_->lower.array() <= lower.array()).all() && (upper.array() <= run_->upper.array()).all();
  }

  // The run's box: whether it holds this segment's box, proving a new one first when it does not
  // (and the chain has not failed too often). A new box holds this segment's two ends and the
  // nominal values of the next kRunWaypoints waypoints: a later segment of the chain starts from
  // its neighbour's intervals, clipped at its nominal value (warm_start), so unless it widens its
  // box lies inside that one.
  bool in_run_box() {
    if (!run_) return false;
    if (run_box_holds(a_, b_)) return true;
    if (run_->failures >= kMaxRunFailures) return false;
    auto [box_lower, box_upper] = segment_box(a_, b_);
    const size_t last = std::min(a_ + kRunWaypoints, e_.q.size() - 1);
    CertifyBudget budget = budget_;
    budget.max_leaves = std::max(64L, budget_.max_leaves / kRunBudgetDivisor);
    for (size_t k = b_ + 1; k <= last; ++k) {
      box_lower = box_lower.cwiseMin(e_.q[k]);
      box_upper = box_upper.cwiseMax(e_.q[k]);
    }
    const long before = stats_.leaves;
    const bool proven = certifier_.region_free(ctx_, box_lower, box_upper, budget, stats_);
    s_.run_leaves += stats_.leaves - before;
    if (proven) {
      run_->lower = box_lower;
      run_->upper = box_upper;
      run_->proven = true;
      return true;
    }
    ++run_->failures;
    return false;
  }

  void shrink_until_certified() {
    if (in_run_box()) {
      s_.passed = s_.run = true;
      return;
    }
    CertifyFailure f;
    while (s_.shrink_steps < kMaxShrinkSteps) {
      f = CertifyFailure{};
      if (probed(a_, b_, &f) && certified(a_, b_, &f)) {
        s_.passed = true;
        break;
      }
      if (out_of_budget()) {
        // Shrinking further would prove nothing more: the segment is not certified.
        s_.budget_exhausted = true;
        break;
      }
      ++s_.shrink_steps;
      if (!shrink_for(f)) break;  // nothing left to shrink: the nominal segment itself is not certified
    }
    if (!s_.passed) {
      for (size_t k : {a_, b_}) {
        e_.below[k].setZero();
        e_.above[k].setZero();
      }
      describe_block(f);
    }
  }

  // What stopped the proof of this segment: the failing pair, where, and its distance there.
  void describe_block(const CertifyFailure& f) {
    if (f.link_geom < 0 || f.obstacle_geom < 0) return;
    s_.blocking_link = f.link_geom;
    s_.blocking_other = f.obstacle_geom;
    s_.blocking_self = f.self;
    s_.blocking_t = a_ == b_ ? 0.0 : (f.t0 + f.t1) / 2;
    RobotState state(ctx_.scene());
    state.set((1 - s_.blocking_t) * e_.q[a_] + s_.blocking_t * e_.q[b_]);
    const mjModel& m = ctx_.scene().model();
    s_.blocking_distance = shape_distance(geom_shape(m, state.data(), f.link_geom),
                                          geom_shape(m, state.data(), f.obstacle_geom));
  }

  // Halves the blamed joint's extent on its side (`above`), or with joint < 0 every extent, at the
  // waypoints `at`; false when nothing was left to halve.
  bool shrink(const std::vector<size_t>& at, int joint, bool above) {
    bool any = false;
    for (size_t k : at)
      for (int i = 0; i < n_; ++i)
        for (int side = 0; side < 2; ++side) {
          if (joint >= 0 && (i != joint || side != (above ? 1 : 0))) continue;
          double& extent = side ? e_.above[k][i] : e_.below[k][i];
          if (extent > 0) {
            halve(extent);
            any = true;
          }
        }
    return any;
  }

  // One shrink step for failure f; false when nothing is left to shrink.
  bool shrink_for(const CertifyFailure& f) {
    const size_t a = a_, b = b_;
    const double tm = (f.t0 + f.t1) / 2;
    std::vector<size_t> ends;
    if (a == b || 1 - tm >= 0.25) ends.push_back(a);
    if (a != b && tm >= 0.25) ends.push_back(b);
    const int j = f.split_joint;
    const bool above = j >= 0 && f.lower.size() == n_ &&
                       (f.lower[j] + f.upper[j]) / 2 >= (1 - tm) * e_.q[a][j] + tm * e_.q[b][j];
    const std::vector<size_t> both = a == b ? std::vector<size_t>{a} : std::vector<size_t>{a, b};
    return (j >= 0 && (shrink(ends, j, above) || shrink(both, j, above))) || shrink(ends, -1, above) ||
           shrink(both, -1, above);
  }

  // Growing one extent (waypoint k, joint i, side) from `from` to `to` adds to a certified segment
  // (p, r), k one of its ends, exactly the configurations whose joint i lies between the old and the
  // new bound: at each t a box, linear in t between the two ends (at the end other than k the
  // slab has zero width). That slab is itself a segment for the certificate, and a thin one.
  struct Slab {
    Eigen::VectorXd lower[2], upper[2];  // at the segment's two ends
  };
  Slab slab(size_t p, size_t r, size_t k, int i, int side, double from, double to) const {
    Slab slab{{e_.lower(p), e_.lower(r)}, {e_.upper(p), e_.upper(r)}};
    for (size_t end = 0; end < 2; ++end) {
      const size_t x = end ? r : p;
      const double now = side ? e_.above[x][i] : e_.below[x][i];
      const double old_extent = x == k ? from : now, new_extent = x == k ? to : now;
      if (side) {
        slab.lower[end][i] = e_.q[x][i] + old_extent;
        slab.upper[end][i] = e_.q[x][i] + new_extent;
      } else {
        slab.lower[end][i] = e_.q[x][i] - new_extent;
        slab.upper[end][i] = e_.q[x][i] - old_extent;
      }
    }
    return slab;
  }

  // Whether the segment (p, r) that shares waypoint k was certified before this step: then a slab
  // of it needs only the pairs joint i moves (Certifier::segment_free); else every pair.
  bool region_certified(size_t p, size_t r) const {
    return (p == a_ && r == b_) || (p < a_ ? nb_.previous_certified : nb_.next_certified);
  }

  bool slab_certified(size_t p, size_t r, size_t k, int i, int side, double from, double to,
                      long budget_divisor) {
    const Slab s = slab(p, r, k, i, side, from, to);
    CertifyBudget thin = budget_;
    thin.max_leaves = std::max(64L, budget_.max_leaves / budget_divisor);
    return certifier_.segment_free(ctx_, s.lower[0], s.upper[0], s.lower[1], s.upper[1], thin, stats_,
                                   nullptr, nullptr, region_certified(p, r) ? i : -1);
  }

  // The probe of the slab's outer face (joint i at the new extent at waypoint k, at its bound at the
  // other end): the rest of the segment was proven free with the old extent, so only configurations
  // the growth adds need checking, and where it hits, it hits first at its outer face in most cases
  // (the certificate still proves the whole slab). Half the corners of the segment's probe, and only
  // the pairs joint i moves.
  bool face_probed(size_t p, size_t r, size_t k, int i, int side, double to) {
    const Slab s = slab(p, r, k, i, side, to, to);
    return certifier_.segment_probe(ctx_, s.lower[0], s.upper[0], s.lower[1], s.upper[1], e_.q[p], e_.q[r],
                                    kProbeSamples, stats_, nullptr, budget_.leaf_limit,
                                    region_certified(p, r) ? i : -1);
  }

  void regrow() {
    // (Without a shrink, only a widening end b has something to regrow.)
    std::vector<size_t> ends;
    if (s_.shrink_steps > 0) ends.push_back(a_);
    if (b_ != a_) ends.push_back(b_);
    for (int i = 0; i < n_ && !out_of_budget(); ++i)
      for (size_t k : ends)
        for (int side = 0; side < 2 && !out_of_budget(); ++side) regrow_extent(k, i, side);
  }

  // The probe of this segment and of the neighbours that share waypoint k, at the extents set (joint
  // i's extent on `side` at k being the one regrown from `from`). On a short segment, only the faces
  // of the slabs the growth adds (face_probed): a dense path regrows hundreds of segments, and
  // probing each whole segment again repeats checks of what is already proven.
  bool probe_all(size_t k, int i, int side, double from) {
    if (short_) {
      const double to = side ? e_.above[k][i] : e_.below[k][i];
      if (!(to > from)) return true;
      return all_at(k, [&](size_t p, size_t r) { return face_probed(p, r, k, i, side, to); });
    }
    return all_at(k, [&](size_t p, size_t r) { return probed(p, r, nullptr); });
  }

  // Whether `test` holds for this segment and for the neighbours that share waypoint k and ran
  // before it (a regrown waypoint must keep them certified), in that order, stopping at the first
  // that fails.
  template <class Test>
  bool all_at(size_t k, Test test) {
    const bool previous = nb_.check_previous && k == a_, next = nb_.check_next && k == b_ && a_ != b_;
    return test(a_, b_) && (!previous || test(a_ - 1, a_)) && (!next || test(b_, b_ + 1));
  }

  void regrow_extent(size_t k, int i, int side) {
    double& extent = side ? e_.above[k][i] : e_.below[k][i];
    const size_t end = k == b_ ? 1 : 0;
    const double shrunk_to = extent, guide_extent = side ? target_above_[end][i] : target_below_[end][i];
    if (!(guide_extent > shrunk_to)) return;
    // A widening the chain was refused before is not tried again (RunBox).
    const bool widening = widen_b_ && s_.shrink_steps == 0 && run_;
    if (widening && run_->refused[static_cast<size_t>(2 * i + side)]) return;
    // Inside the run's box the whole way back needs no proof (nor a probe) ...
    extent = guide_extent;
    if (all_at(k, [&](size_t p, size_t r) { return run_box_holds(p, r); })) return;
    // ... else the largest extent the probe does not reject, by bisection (cheap) ...
    double ok = shrunk_to, bad = guide_extent;
    if (probe_all(k, i, side, shrunk_to)) {
      ok = bad;
    } else {
      for (int step = 0; step < kProbeSteps; ++step) {
        extent = (ok + bad) / 2;
        const bool pass = probe_all(k, i, side, shrunk_to);
        (pass ? ok : bad) = extent;
      }
    }
    // ... then the largest the certificate proves, between the shrunk value and that one: the
    // probe's limit and a thin slab an eighth of the way to it (when the thin slab cannot be
    // proven, the thicker ones are not either, almost always: the extent stays shrunk), then
    // bisection. On a short segment the thin slab comes first, on a small budget: on dense paths it
    // fails in most cases, and a failing slab costs its whole budget.
    const double probe_limit = ok;
    ok = shrunk_to;
    bad = probe_limit;
    const int thin_step = short_ ? 0 : 1, limit_step = 1 - thin_step;
    for (int step = 0; step < kRegrowSteps && bad - ok > kTinyExtent; ++step) {
      extent = step == limit_step ? bad : step == thin_step ? ok + (bad - ok) / 8 : (ok + bad) / 2;
      const long divisor = short_ && step == thin_step ? kThinSlabBudgetDivisor : kSlabBudgetDivisor;
      // Only what the growth adds needs proving: the rest was proven with extent `ok`.
      const bool pass = all_at(
          k, [&](size_t p, size_t r) { return slab_certified(p, r, k, i, side, ok, extent, divisor); });
      if (pass) {
        ok = extent;
        if (step == limit_step) break;
      } else {
        bad = extent;
        if (step == thin_step) break;
      }
    }
    extent = ok;
    if (widening && ok == shrunk_to && probe_limit > shrunk_to)
      run_->refused[static_cast<size_t>(2 * i + side)] = 1;
  }

  const Certifier& certifier_;
  CertifyContext& ctx_;
  Extents& e_;
  const Extents& guide_;
  const size_t a_, b_;
  const Neighbours nb_;
  const int n_;
  const bool short_;
  RunBox* const run_;  // the chain's run box (dense paths, short segments), or null
  CertifyBudget budget_;
  SegmentSafety s_;
  CertifyStats stats_;
  // Stretches of this segment proven free so far: valid while its bounds only shrink.
  std::vector<std::pair<double, double>> proven_;
  // Regrow targets per end (0: a, 1: b).
  Eigen::VectorXd target_below_[2], target_above_[2];
  bool widen_b_ = false;
};

// Sampled mode for one segment: rounds of N samples drawn as leeway cf draws them (t uniform, every
// joint uniform within the interpolated bounds); a round with a collision scales every extent at
// both ends by 0.8 and the test starts again with fresh samples.
SegmentSafety sample_segment(RobotState& state, Extents& e, size_t a, size_t b, long n_samples,
                             std::uint64_t seed, size_t segment) {
  SegmentSafety s;
  const int n = static_cast<int>(e.q[a].size());
  bool nominal = false;  // every extent of both ends is zero
  for (int round = 0; round < 200; ++round) {
    ++s.rounds;
    std::mt19937_64 rng(splitmix(seed ^ splitmix(segment * 1000003ULL + static_cast<std::uint64_t>(round))));
    const Eigen::VectorXd la = e.lower(a), ua = e.upper(a), lb = e.lower(b), ub = e.upper(b);
    bool hit = false;
    Eigen::VectorXd q(n);
    for (long k = 0; k < n_samples && !hit; ++k) {
      const double t = a == b ? 0.0 : unit(rng);
      detail::draw_in_segment(la, ua, lb, ub, t, rng, q);
      ++s.samples;
      hit = state.in_collision(q);
    }
    if (!hit) {
      s.passed = true;
      return s;
    }
    // Already down to the nominal segment and still hit: nothing is left to shrink.
    if (nominal) return s;
    nominal = true;
    for (size_t k : {a, b})
      for (int i = 0; i < n; ++i)
        for (double* extent : {&e.below[k][i], &e.above[k][i]}) {
          *extent = *extent * 0.8 < kTinyExtent ? 0.0 : *extent * 0.8;
          nominal = nominal && *extent == 0;
        }
    ++s.shrink_steps;
  }
  return s;
}

// The certifier's options: each segment counts its leaves from zero (its own CertifyStats) up to
// segment_leaf_budget, passed to each call. Pivot boxes only for a sparse path's growth: the
// shrink and regrow keep the guide's narrow wrist, where they cost more time than they prove, and
// the dense growth's time limits were measured without them (docs/algorithm.md, "Pivot boxes").
CertifyOptions certify_options(const SafetyParams& params, const SweepBound* bound, bool pivot_boxes) {
  CertifyOptions options;
  options.margin = params.margin;
  options.max_leaves = params.max_leaves;
  options.bound = bound;
  options.pivot_boxes = pivot_boxes;
  return options;
}

}  // namespace

long segment_leaf_budget(const SafetyParams& params) {
  return kSegmentLeafBudgetFactor * static_cast<long>(params.max_leaves);
}

long sampled_test_size(double epsilon, double delta) {
  return static_cast<long>(std::ceil(std::log(1.0 / delta) / epsilon));
}

SafetyReport make_safe(const Scene& scene, std::vector<WaypointBounds>& bounds, const SafetyParams& params,
                       int threads, const SweepBound* bound) {
  SafetyReport report;
  report.mode = params.mode;
  if (params.mode == SafetyMode::kNone || bounds.empty()) return report;
  const auto t0 = std::chrono::steady_clock::now();
  require_joint_counts(scene, bounds);
  for (size_t k = 0; k < bounds.size(); ++k) {
    const auto& w = bounds[k];
    if (!(w.lower.array() <= w.q.array()).all() || !(w.q.array() <= w.upper.array()).all())
      throw InputError("bounds of waypoint " + std::to_string(k) + " do not contain the nominal value");
  }
  Extents e(bounds);
  const size_t segments = std::max<size_t>(1, bounds.size() - 1);
  // A dense path: at least half its segments short.
  size_t short_count = 0;
  for (size_t s = 0; s + 1 < bounds.size(); ++s) short_count += is_short(e, s, s + 1) ? 1 : 0;
  const bool dense = 2 * short_count >= segments && segments > 1;
  if (params.mode == SafetyMode::kCertified) {
    const Certifier certifier(scene, certify_options(params, bound, false));
    const long leaf_limit = segment_leaf_budget(params);
    const Extents guide(bounds);
    // Segment s writes waypoints s and s + 1 and, regrowing them, reads its neighbours' (s - 1 and
    // s + 2): segments three apart share nothing, so the segments with s % phases == phase run in
    // parallel, phase by phase. A regrown waypoint must keep the neighbour that shares it certified
    // when that neighbour's phase came earlier. The order does not depend on the thread count.
    report.segments.assign(segments, SegmentSafety{});
    std::vector<CertifyStats> stats(segments);
    // A dense path (at least half its segments short) takes kDensePhases phases: every segment but
    // those of phase 0 then has a settled neighbour to start warm from.
    const size_t phases = dense ? kDensePhases : 3;
    // One run box per chain of warm starts (the segments of one chain run one after another).
    RunBox fresh;
    fresh.refused.assign(static_cast<size_t>(2 * scene.dof()), 0);
    std::vector<RunBox> runs(dense && params.runs ? segments / phases + 1 : 0, fresh);
    for (size_t phase = 0; phase < phases; ++phase) {
      std::vector<size_t> jobs;
      for (size_t s = phase; s < segments; s += phases) jobs.push_back(s);
      detail::parallel_for(static_cast<int>(jobs.size()), threads, [&] {
        auto ctx = std::make_shared<CertifyContext>(scene);
        return [&, ctx](int i) {
          const size_t s = jobs[static_cast<size_t>(i)];
          Neighbours nb;
          nb.check_previous = s > 0 && phase > 0;
          nb.check_next = s + 1 < segments && phase == phases - 1;
          // The neighbours ran in earlier phases: their outcome is settled.
          nb.previous_certified = nb.check_previous && report.segments[s - 1].passed;
          nb.next_certified = nb.check_next && report.segments[s + 1].passed;
          SegmentRepair repair(certifier, *ctx, leaf_limit, e, guide, s, std::min(s + 1, bounds.size() - 1),
                               nb, runs.empty() ? nullptr : &runs[s / phases]);
          report.segments[s] = repair.run(stats[s]);
        };
      });
    }
    for (const auto& st : stats) report.stats.add(st);
    for (const auto& seg : report.segments) {
      report.run_segments += seg.run ? 1 : 0;
      report.run_leaves += seg.run_leaves;
    }
  } else {
    report.samples_per_segment = sampled_test_size(params.epsilon, params.delta);
    RobotState state(scene);
    // A later segment's shrink also shrinks the earlier segment that shares its waypoint: repeat
    // the pass until one pass shrinks nothing, so every segment's final region passed its test.
    // Per segment: samples, rounds and shrink steps add up over the passes; `passed` is the last's.
    report.segments.assign(segments, SegmentSafety{});
    for (int pass = 0; pass < 8; ++pass) {
      bool any_shrunk = false;
      for (size_t s = 0; s < segments; ++s) {
        const auto r =
            sample_segment(state, e, s, std::min(s + 1, bounds.size() - 1), report.samples_per_segment,
                           params.seed + static_cast<std::uint64_t>(pass), s);
        any_shrunk = any_shrunk || r.shrink_steps > 0;
        SegmentSafety& total = report.segments[s];
        total.passed = r.passed;
        total.samples += r.samples;
        total.rounds += r.rounds;
        total.shrink_steps += r.shrink_steps;
      }
      if (!any_shrunk) break;
    }
  }
  for (const auto& s : report.segments) report.all_passed = report.all_passed && s.passed;
  // Only shrunk sides are rewritten, so an untouched bound keeps its exact value.
  const Extents original(bounds);
  for (size_t k = 0; k < bounds.size(); ++k)
    for (Eigen::Index i = 0; i < bounds[k].q.size(); ++i) {
      if (e.below[k][i] != original.below[k][i]) bounds[k].lower[i] = bounds[k].q[i] - e.below[k][i];
      if (e.above[k][i] != original.above[k][i]) bounds[k].upper[i] = bounds[k].q[i] + e.above[k][i];
    }
  // Growth, waypoint by waypoint on a sparse path; on a dense one by blocks of segments, each grown
  // as one box, since waypoint by waypoint it cost several times the certified mode's work
  // (docs/algorithm.md, "Growing"). The caps apply to every path.
  if (params.mode == SafetyMode::kCertified && (params.grow != "none" || !params.max_half_width.empty())) {
    report.grow = dense ? grow_dense(scene, bounds, report.segments, params,
                                     certify_options(params, bound, false), threads)
                        : grow_bounds(scene, bounds, report.segments, params,
                                      certify_options(params, bound, true), threads);
    report.stats.add(report.grow.stats);
  }
  report.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

}  // namespace leeway
