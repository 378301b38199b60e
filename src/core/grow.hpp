#pragma once
// Internal: the safety stage's growth beyond the guide (docs/algorithm.md, "Growing"; not public
// API: make_safe runs it).

#include <Eigen/Core>
#include <vector>

#include "leeway/core/bounds.hpp"
#include "leeway/core/certify.hpp"
#include "leeway/core/params.hpp"
#include "leeway/core/safety.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {

//! The joints params.grow names ("all", "none" or names separated by commas), one flag per joint.
//! @throws InputError naming the scene and an unknown joint.
std::vector<bool> grow_mask(const Scene& scene, const SafetyParams& params);

//! params.max_half_width per joint (infinite where a joint is not named) [rad or m].
//! @throws InputError naming the scene and an unknown joint.
Eigen::VectorXd half_width_caps(const Scene& scene, const SafetyParams& params);

//! Certified bounds (`segments` says which segments were proven) made wider, every growth proven:
//! first every interval is capped at params.max_half_width; then each side of each grown joint at
//! each waypoint whose segments are all certified is widened toward the end of the joint's
//! one-joint free range (probe, then a certified slab, then bisection when it fails), in rounds
//! tip to base (params.shape "greedy") or in one pass, cheapest share first ("lever").
//! Even waypoints, then odd ones, run in parallel on `threads` threads; the result does not depend
//! on the thread count.
GrowReport grow_bounds(const Scene& scene, std::vector<WaypointBounds>& bounds,
                       const std::vector<SegmentSafety>& segments, const SafetyParams& params,
                       const CertifyOptions& options, int threads);

//! grow_bounds for a dense path: blocks of 16 consecutive segments, each grown as one box. The
//! hull of a block's waypoint boxes (which holds each of its segments' regions) is proven free
//! first; then each side of each grown joint, tip to base in one pass, is widened toward the
//! joint's limit (capped) at every waypoint of the block to the same extent: a probe of the hull's
//! new face walks outward and bisects, and the box slab the step adds to the hull is proven (only
//! the pairs the joint moves). Even blocks, then odd ones, run in parallel; an odd block keeps its
//! end waypoints as the even blocks left them, or gives them back when it cannot grow. The result
//! does not depend on the thread count.
GrowReport grow_dense(const Scene& scene, std::vector<WaypointBounds>& bounds,
                      const std::vector<SegmentSafety>& segments, const SafetyParams& params,
                      const CertifyOptions& options, int threads);

}  // namespace leeway
