#pragma once
//! @file bounds_trajectory.hpp
//! The bounds as a controller reads them: a box of joint values at every point of the path, in the
//! path parameter s and in the nominal time t (docs/cli.md, "Contract for a controller").
//!
//! The path parameter s runs from 0 at the first waypoint to N - 1 at the last: waypoint i is at
//! s = i, and s = i + f (0 <= f <= 1) is the fraction f of the segment from waypoint i to i + 1.
//! Between waypoints the nominal value, the lower and the upper bound of every joint are linear in
//! s. The nominal time t of waypoint i is when the nominal path reaches it with every segment
//! lasting as long as its slowest joint needs at its nominal speed (time_path()); on an untimed
//! path (a joint without a speed) every segment lasts 1 and t = s.

#include <Eigen/Core>
#include <utility>
#include <vector>

#include "leeway/core/bounds.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {

//! The box at one point of the path [rad or m per joint].
struct BoundsStage {
  double t = 0;             //!< nominal time [s] (the path parameter on an untimed path)
  double s = 0;             //!< path parameter: waypoint index plus the fraction of the segment
  Eigen::VectorXd nominal;  //!< the nominal configuration there
  Eigen::VectorXd lower;    //!< lower bound per joint
  Eigen::VectorXd upper;    //!< upper bound per joint
};

//! Most rows sample() gives (and `leeway sample` writes).
inline constexpr long kMaxSampleRows = 10'000'000;

//! A bounded path with its nominal timing. Immutable once built; every query is const and safe to
//! call from several threads.
//!
//! Out of range: s below 0 or above N - 1, and t below 0 or above duration(), are clamped to the
//! path's ends (the first or last waypoint's box, which the bounds cover like any other point: a
//! controller that holds the robot before the start or after the end stays inside them). NaN is
//! refused.
class BoundsTrajectory {
 public:
  //! The bounds timed by the scene's joint speeds (time_path()).
  //! @throws InputError when the bounds do not match the scene or are not well formed (see below).
  BoundsTrajectory(const Scene& scene, std::vector<WaypointBounds> bounds);

  //! The bounds with the given nominal time of each waypoint [s] (a bounds file's "t"): the first
  //! 0, then non-decreasing. `timed` false says the times are the path parameter (no joint speeds).
  //! @throws InputError on no waypoint, sizes that differ, a value that is not finite, lower > q or
  //! q > upper, or times that are not as above.
  BoundsTrajectory(std::vector<WaypointBounds> bounds, std::vector<double> times, bool timed);

  int dof() const { return static_cast<int>(bounds_.front().q.size()); }
  int waypoint_count() const { return static_cast<int>(bounds_.size()); }
  const std::vector<WaypointBounds>& waypoints() const { return bounds_; }
  //! The nominal time of every waypoint [s].
  const std::vector<double>& times() const { return times_; }
  //! True when the times come from joint speeds; false when t = s.
  bool timed() const { return timed_; }
  //! The nominal path's duration [s]: the time of the last waypoint.
  double duration() const { return times_.back(); }
  //! The path parameter at the last waypoint: N - 1.
  double s_end() const { return static_cast<double>(bounds_.size() - 1); }

  //! The path parameter at nominal time t (clamped to [0, duration()]). At the moment of a segment of
  //! zero duration (a waypoint given twice) the later waypoint's s.
  //! @throws InputError when t is NaN.
  double s_at_t(double t) const;
  //! The nominal time at path parameter s (clamped to [0, s_end()]).
  //! @throws InputError when s is NaN.
  double t_at_s(double s) const;

  //! The box at path parameter s; at s = i it is waypoint i's, value for value.
  //! @throws InputError when s is NaN.
  BoundsStage at_s(double s) const;
  //! The box at nominal time t: at_s(s_at_t(t)).
  //! @throws InputError when t is NaN.
  BoundsStage at_t(double t) const;
  //! at_s writing into caller-owned vectors of dof() values (no allocation: a control loop's call).
  //! @throws InputError when s is NaN (the vectors' sizes are the caller's to get right).
  void at_s(double s, Eigen::Ref<Eigen::VectorXd> nominal, Eigen::Ref<Eigen::VectorXd> lower,
            Eigen::Ref<Eigen::VectorXd> upper) const;
  //! at_t writing into caller-owned vectors, as at_s.
  void at_t(double t, Eigen::Ref<Eigen::VectorXd> nominal, Eigen::Ref<Eigen::VectorXd> lower,
            Eigen::Ref<Eigen::VectorXd> upper) const;

  //! Rows at t = 0, dt, 2 dt, ... and at t = duration() (once, also when it is a multiple of dt).
  //! @throws InputError when dt is not a positive finite number or the rows would exceed
  //! kMaxSampleRows.
  std::vector<BoundsStage> sample(double dt) const;
  //! How many rows sample(dt) gives, without building them.
  //! @throws InputError as sample().
  long sample_count(double dt) const;

  //! True when lower(s) <= q <= upper(s) in every joint.
  //! @throws InputError when s is NaN or q has another size than dof().
  bool contains(double s, const Eigen::VectorXd& q) const;

  //! The segment and the fraction of it at a share u in [0, 1] of the duration: what the Confidence
  //! Factor draws (the last segment starting at or before u, so a segment of zero duration is never
  //! drawn). On a one-waypoint path {0, 0}.
  std::pair<int, double> locate_share(double u) const;
  //! The segment and the fraction of it at path parameter s (clamped): {i, f} with s = i + f.
  std::pair<int, double> locate_s(double s) const;

 private:
  void validate() const;
  void interpolate(int segment, double f, Eigen::Ref<Eigen::VectorXd> nominal,
                   Eigen::Ref<Eigen::VectorXd> lower, Eigen::Ref<Eigen::VectorXd> upper) const;

  std::vector<WaypointBounds> bounds_;
  std::vector<double> times_;        // nominal time of each waypoint [s]
  std::vector<double> share_start_;  // share of the duration at each segment's start, then 1
  bool timed_ = false;
};

//! Reads a bounds file (format 1 or 2) as a trajectory for `scene`: read_bounds(), then the file's
//! times (format 2) or the scene's timing (format 1, which has none).
//! @throws InputError as read_bounds, and on times that are missing, not finite or decreasing.
BoundsTrajectory read_bounds_trajectory(const std::string& path, const Scene& scene);

}  // namespace leeway
