#pragma once
//! @file bounds.hpp
//! Jointspace exploration (thesis section 3.3): Algorithm 2 (bisection of one joint's bound against
//! the volume) and Algorithm 3 (the joint hierarchy), with the collapse guard and the fixed
//! intervals of the wrist joints and the linear axis.

#include <Eigen/Core>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "leeway/core/params.hpp"
#include "leeway/core/scene.hpp"
#include "leeway/core/volume_world.hpp"

namespace leeway {

//! A collision predicate over configurations.
using CollisionFn = std::function<bool(const Eigen::VectorXd&)>;

//! Algorithm 2: the upper bound of joint j around q (the other joints stay as in q). Checks the
//! joint at its absolute limit first and returns it when free (an obstacle met only in the middle
//! of the sweep is then not seen, as in the thesis); otherwise bisects between q[j] and the limit
//! while the probe B is more than `delta` above the highest collision-free value A (the thesis's
//! loop condition: the final bracket [A, C] can be up to 2 delta wide), and returns A (q[j] itself
//! when every probe collides). `checks` is incremented per collision check.
//! bound_upper and bound_lower share one implementation; they are two functions so that each call
//! site reads as the thesis's Algorithm 2 or its mirror image (docs/algorithm.md names both), and
//! so that each checks that `limit` lies on its side of q[j].
//! @throws InputError when j is not an index of q or limit < q[j].
double bound_upper(const CollisionFn& collides, Eigen::VectorXd q, int j, double limit, double delta,
                   long& checks);

//! The symmetric lower-bound version of Algorithm 2 (see bound_upper).
//! @throws InputError when j is not an index of q or limit > q[j].
double bound_lower(const CollisionFn& collides, Eigen::VectorXd q, int j, double limit, double delta,
                   long& checks);

//! How a joint's interval was obtained.
enum class BoundKind {
  kBisected,  //!< Algorithms 2 and 3 (bounds.bisect, by default the first three hinge joints)
  kFixed,     //!< a fixed half-width around nominal (the other hinge joints: the wrist)
  kLinear,    //!< a fraction of the range around nominal (slide joints: the linear axis)
};

//! The bounds of one waypoint. Default-constructed it is empty (the library's algorithms fill it);
//! the three-vector constructor checks what it is given.
struct WaypointBounds {
  WaypointBounds() = default;
  //! Bounds [lower, upper] around the nominal q, nothing collapsed, guide bounds equal to these.
  //! @throws InputError when the sizes differ, a value is not finite or lower <= q <= upper fails.
  WaypointBounds(Eigen::VectorXd q, Eigen::VectorXd lower, Eigen::VectorXd upper);

  //! True when lower <= c <= upper in every joint.
  //! @throws InputError when c's size differs from the bounds'.
  bool contains(const Eigen::VectorXd& c) const;

  //! What the safety stage took off joint i's guide interval [rad or m]: {from below, from above}, negative
  //! on a side its growth widened;
  //! {0, 0} when no guide is recorded (bounds read from a file).
  std::pair<double, double> shrunk_by(Eigen::Index i) const;

  Eigen::VectorXd q;               //!< nominal configuration
  Eigen::VectorXd lower;           //!< lower bound per joint [rad or m]
  Eigen::VectorXd upper;           //!< upper bound per joint [rad or m]
  std::vector<bool> collapsed;     //!< the collapse guard widened this joint's interval
  bool nominal_in_volume = false;  //!< the nominal configuration itself touches the volume
  //! The bounds Algorithms 2 and 3 gave before the safety stage shrank them (equal to lower/upper
  //! when nothing was shrunk or the safety mode is none).
  Eigen::VectorXd guide_lower, guide_upper;
  long checks = 0;  //!< collision checks spent on this waypoint
};

//! Algorithm 3 at one waypoint, using `collides` for the volume checks. Bounds always contain the
//! nominal value and stay within the joint limits.
WaypointBounds bound_waypoint(const Scene& scene, const CollisionFn& collides, const Eigen::VectorXd& q,
                              const BoundsParams& params);

//! Checks that every waypoint's q, lower and upper have one value per joint of `scene`.
//! @throws InputError naming the waypoint and the scene otherwise.
void require_joint_counts(const Scene& scene, const std::vector<WaypointBounds>& bounds);

//! The kind of every joint, in order: the hinge joints named in `params.bisect` (when it is empty,
//! the first three hinge joints) are bisected, the other hinge joints fixed, slide joints linear.
//! @throws InputError naming the scene, the parameter and the joint when `params.bisect` names a
//! joint the scene does not have or a slide joint.
std::vector<BoundKind> bound_kinds(const Scene& scene, const BoundsParams& params);

//! The fixed half-width of joint `index` of kind kFixed or kLinear [rad or m]: its entry in
//! `params.half_width`, otherwise wrist_half_width (hinge) or linear_axis_tolerance x range (slide).
double fixed_half_width(const Scene& scene, int index, const BoundsParams& params);

//! Bounds of every waypoint against the volume in `world`, spread over `threads` threads (one
//! VolumeChecker each): one waypoint per task when there are at least as many waypoints as threads,
//! otherwise waypoint after waypoint with the 2, 4, 8 ... Algorithm-2 runs of each joint level of
//! Algorithm 3 spread over the threads. Deterministic: the result, checks included, does not depend
//! on the thread count.
std::vector<WaypointBounds> bound_path(const VolumeModel& world, const std::vector<Eigen::VectorXd>& path,
                                       const BoundsParams& params, int threads);

}  // namespace leeway
