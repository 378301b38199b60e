#pragma once
//! @file safety.hpp
//! The safety stage after Algorithms 2 and 3: shrinks the guide bounds until the whole bounded path
//! (every waypoint box and every segment between waypoints, as leeway cf samples it) is certified
//! free of the real obstacles, or passes an (epsilon, delta) sampling test. docs/algorithm.md.

#include <Eigen/Core>
#include <vector>

#include "leeway/core/bounds.hpp"
#include "leeway/core/certify.hpp"
#include "leeway/core/params.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {

//! The outcome for one segment (waypoint k to k + 1; a one-waypoint path has one "segment").
struct SegmentSafety {
  bool passed = false;   //!< certified (certified mode) or sampling test passed (sampled mode)
  long leaves = 0;       //!< certificate leaves spent on this segment, repairs included
  int max_depth = 0;     //!< deepest subdivision
  int shrink_steps = 0;  //!< shrink steps the repair took
  long samples = 0;      //!< sampled mode: configurations drawn, all rounds and passes
  int rounds =
      0;  //!< sampled mode: sampling rounds, all passes (the last one found no collision when passed)
  //! Certified mode: the segment's leaf budget (segment_leaf_budget) ran out. Before the segment was
  //! proven, it is not certified and keeps its nominal values; after (while regrowing), it keeps
  //! the bounds proven so far, narrower than the search would have made them.
  bool budget_exhausted = false;
  //! Certified mode, dense paths: proven by its chain's run box (docs/algorithm.md, "Run boxes":
  //! one proof of a box holding this and the next segments), its own or an earlier segment's.
  bool run = false;
  long run_leaves = 0;  //!< leaves this segment spent on run boxes, proven or not (in `leaves` too)
  //! Certified mode, not passed: the pair that stopped the last proof (a link geom and an obstacle,
  //! or another robot geom when `blocking_self`; -1 when the budget ran out before any pair failed),
  //! where along the segment (t in [0, 1], from waypoint a to b) and the distance of the two geoms'
  //! shapes at the nominal configuration there [m] (0 in contact).
  int blocking_link = -1, blocking_other = -1;
  bool blocking_self = false;
  double blocking_t = 0.0;
  double blocking_distance = 0.0;
};

//! The certified mode's work limit per segment, in multiples of SafetyParams::max_leaves: every
//! leaf the segment costs (probe checks, the proofs of every shrink step, the regrow's probes and
//! slabs, its neighbours' slabs included) counts. The stage as a whole spends at most this times
//! max_leaves times the number of segments, whatever the joint count.
constexpr long kSegmentLeafBudgetFactor = 128;

//! The leaf budget of one segment: kSegmentLeafBudgetFactor * max_leaves.
long segment_leaf_budget(const SafetyParams& params);

//! What the growth beyond the guide did (certified mode, params.grow not "none").
struct GrowReport {
  bool ran = false;    //!< growth ran (certified mode, some joint to grow)
  int grown = 0;       //!< intervals (waypoint x joint) now wider than the guide's on some side
  CertifyStats stats;  //!< certificate work of the growth (in SafetyReport::stats too)
  double ms = 0;       //!< wall time [ms] (in SafetyReport::ms too)
};

//! What the safety stage did.
struct SafetyReport {
  SafetyMode mode = SafetyMode::kNone;
  bool all_passed = true;  //!< every segment certified (or passed the sampling test)
  std::vector<SegmentSafety> segments;
  CertifyStats stats;            //!< certificate work, all segments
  long samples_per_segment = 0;  //!< sampled mode: N = ceil(ln(1/delta) / epsilon)
  double ms = 0;                 //!< wall time of the stage [ms]
  GrowReport grow;               //!< certified mode: the growth beyond the guide
  int run_segments = 0;          //!< certified mode: segments proven by a run's box (SegmentSafety::run)
  long run_leaves = 0;           //!< certified mode: leaves spent on run boxes (in `stats` too)
};

//! Samples one sampling round needs: N = ceil(ln(1/delta) / epsilon). Zero collisions in N uniform
//! samples rejects, with confidence 1 - delta, a region whose collision share exceeds epsilon.
long sampled_test_size(double epsilon, double delta);

//! Runs the safety stage on `bounds` (waypoints in path order, linearly joined) in place: none
//! returns at once; certified shrinks, joint by joint, toward the nominal values until every segment
//! is certified; sampled until every segment passes the sampling test. Bounds never shrink below the
//! nominal value. Deterministic. @throws InputError on bounds that do not fit the scene.
//! Certified mode runs segments three apart in parallel on `threads` threads; the result does not
//! depend on the thread count. `bound` (optional) replaces the certificate's Taylor bound (tests and
//! the benchmark compare the loose lever-arm reference through it).
SafetyReport make_safe(const Scene& scene, std::vector<WaypointBounds>& bounds, const SafetyParams& params,
                       int threads = 1, const SweepBound* bound = nullptr);

}  // namespace leeway
