#include "leeway/core/bounds_trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "leeway/core/confidence.hpp"
#include "leeway/core/error.hpp"

namespace leeway {
namespace {

std::vector<double> times_of(const Scene& scene, const std::vector<WaypointBounds>& bounds) {
  require_joint_counts(scene, bounds);
  return time_path(scene, bounds).segment_start;
}

bool timed_for(const Scene& scene, const std::vector<WaypointBounds>& bounds) {
  return time_path(scene, bounds).timed;
}

void require_number(double v, const char* what) {
  if (std::isnan(v)) throw InputError(std::string(what) + " is NaN; give a number");
}

}  // namespace

BoundsTrajectory::BoundsTrajectory(const Scene& scene, std::vector<WaypointBounds> bounds)
    : BoundsTrajectory(bounds, times_of(scene, bounds), timed_for(scene, bounds)) {}

BoundsTrajectory::BoundsTrajectory(std::vector<WaypointBounds> bounds, std::vector<double> times, bool timed)
    : bounds_(std::move(bounds)), times_(std::move(times)), timed_(timed) {
  validate();
  // The share of the duration at each segment's start, exactly as the Confidence Factor has always
  // computed it, so that its draws are the same sample for sample.
  const size_t n = bounds_.size();
  const size_t segments = std::max<size_t>(1, n - 1);
  const double total = times_.back();
  share_start_.assign(segments + 1, 1.0);
  share_start_[0] = 0.0;
  for (size_t i = 1; i < segments; ++i)
    share_start_[i] = total > 0 ? times_[i] / total : static_cast<double>(i) / static_cast<double>(segments);
}

void BoundsTrajectory::validate() const {
  if (bounds_.empty()) throw InputError("bounds: no waypoint");
  const Eigen::Index n = bounds_.front().q.size();
  for (size_t i = 0; i < bounds_.size(); ++i) {
    const WaypointBounds& w = bounds_[i];
    const std::string where = "bounds waypoint " + std::to_string(i);
    if (w.q.size() != n || w.lower.size() != n || w.upper.size() != n)
      throw InputError(where + ": q, lower and upper need " + std::to_string(n) + " values each");
    if (!w.q.allFinite() || !w.lower.allFinite() || !w.upper.allFinite())
      throw InputError(where + ": a value is not finite");
    for (Eigen::Index j = 0; j < n; ++j)
      if (!(w.lower[j] <= w.q[j] && w.q[j] <= w.upper[j]))
        throw InputError(where + " joint " + std::to_string(j) + ": nominal " + format_number(w.q[j]) +
                         " is not within [" + format_number(w.lower[j]) + ", " + format_number(w.upper[j]) +
                         "]");
  }
  if (times_.size() != bounds_.size())
    throw InputError("bounds: " + std::to_string(times_.size()) + " times for " +
                     std::to_string(bounds_.size()) + " waypoints");
  if (times_[0] != 0)
    throw InputError("bounds: the first waypoint's time " + format_number(times_[0]) + " is not 0");
  for (size_t i = 1; i < times_.size(); ++i)
    if (!std::isfinite(times_[i]) || times_[i] < times_[i - 1])
      throw InputError("bounds waypoint " + std::to_string(i) + ": time " + format_number(times_[i]) +
                       " s is not finite or comes before the previous waypoint's " +
                       format_number(times_[i - 1]) + " s");
}

std::pair<int, double> BoundsTrajectory::locate_share(double u) const {
  const auto& start = share_start_;
  const int seg =
      std::max(0, static_cast<int>(std::upper_bound(start.begin(), start.end() - 1, u) - start.begin()) - 1);
  const double span = start[static_cast<size_t>(seg) + 1] - start[static_cast<size_t>(seg)];
  const double f =
      bounds_.size() == 1 || span <= 0 ? 0.0 : std::min(1.0, (u - start[static_cast<size_t>(seg)]) / span);
  return {seg, f};
}

std::pair<int, double> BoundsTrajectory::locate_s(double s) const {
  require_number(s, "the path parameter s");
  if (bounds_.size() == 1) return {0, 0.0};
  const double c = std::clamp(s, 0.0, s_end());
  const int seg = std::min(static_cast<int>(std::floor(c)), static_cast<int>(bounds_.size()) - 2);
  return {seg, c - seg};
}

double BoundsTrajectory::s_at_t(double t) const {
  require_number(t, "the time t");
  if (bounds_.size() == 1) return 0.0;
  const double c = std::clamp(t, 0.0, duration());
  // The last segment starting at or before t: at the moment of a segment of zero duration, the
  // later waypoint.
  const int seg = std::max(
      0, static_cast<int>(std::upper_bound(times_.begin(), times_.end() - 1, c) - times_.begin()) - 1);
  const double span = times_[static_cast<size_t>(seg) + 1] - times_[static_cast<size_t>(seg)];
  const double f = span > 0 ? std::min(1.0, (c - times_[static_cast<size_t>(seg)]) / span) : 1.0;
  return seg + f;
}

double BoundsTrajectory::t_at_s(double s) const {
  const auto [seg, f] = locate_s(s);
  if (bounds_.size() == 1) return 0.0;
  const double a = times_[static_cast<size_t>(seg)], b = times_[static_cast<size_t>(seg) + 1];
  return f == 1.0 ? b : std::min(b, a + f * (b - a));  // rounding never leaves the segment's times
}

void BoundsTrajectory::interpolate(int segment, double f, Eigen::Ref<Eigen::VectorXd> nominal,
                                   Eigen::Ref<Eigen::VectorXd> lower,
                                   Eigen::Ref<Eigen::VectorXd> upper) const {
  const WaypointBounds& a = bounds_[static_cast<size_t>(segment)];
  if (f == 0.0 || bounds_.size() == 1) {
    nominal = a.q;
    lower = a.lower;
    upper = a.upper;
    return;
  }
  const WaypointBounds& b = bounds_[static_cast<size_t>(segment) + 1];
  if (f == 1.0) {
    nominal = b.q;
    lower = b.lower;
    upper = b.upper;
    return;
  }
  // The same arithmetic as the Confidence Factor's draw (lower_a + f (lower_b - lower_a)).
  for (Eigen::Index j = 0; j < a.q.size(); ++j) {
    nominal[j] = a.q[j] + f * (b.q[j] - a.q[j]);
    lower[j] = a.lower[j] + f * (b.lower[j] - a.lower[j]);
    upper[j] = a.upper[j] + f * (b.upper[j] - a.upper[j]);
    // The three are interpolated apart, so rounding could put the nominal value an ulp outside its
    // box; it is inside in exact arithmetic (lower <= q <= upper at both ends).
    if (lower[j] <= upper[j]) nominal[j] = std::clamp(nominal[j], lower[j], upper[j]);
  }
}

void BoundsTrajectory::at_s(double s, Eigen::Ref<Eigen::VectorXd> nominal, Eigen::Ref<Eigen::VectorXd> lower,
                            Eigen::Ref<Eigen::VectorXd> upper) const {
  const auto [seg, f] = locate_s(s);
  interpolate(seg, f, nominal, lower, upper);
}

void BoundsTrajectory::at_t(double t, Eigen::Ref<Eigen::VectorXd> nominal, Eigen::Ref<Eigen::VectorXd> lower,
                            Eigen::Ref<Eigen::VectorXd> upper) const {
  at_s(s_at_t(t), nominal, lower, upper);
}

BoundsStage BoundsTrajectory::at_s(double s) const {
  BoundsStage out;
  out.nominal.resize(dof());
  out.lower.resize(dof());
  out.upper.resize(dof());
  at_s(s, out.nominal, out.lower, out.upper);
  out.s = std::clamp(s, 0.0, s_end());
  out.t = t_at_s(out.s);
  return out;
}

BoundsStage BoundsTrajectory::at_t(double t) const {
  BoundsStage out = at_s(s_at_t(t));
  out.t = std::clamp(t, 0.0, duration());
  return out;
}

long BoundsTrajectory::sample_count(double dt) const {
  if (!(dt > 0) || !std::isfinite(dt))
    throw InputError("the time step dt " + format_number(dt) + " s must be a positive number");
  const double steps = duration() / dt;
  if (steps >= static_cast<double>(kMaxSampleRows))
    throw InputError("the time step dt " + format_number(dt) + " s would give more than " +
                     std::to_string(kMaxSampleRows) + " rows over the path's " + format_number(duration()) +
                     " s; use a larger step");
  const long k = static_cast<long>(std::floor(steps));
  // The end gets its own row unless k dt already is the end (to rounding).
  const bool end_row = duration() - static_cast<double>(k) * dt > 1e-9 * std::max(1.0, duration());
  const long rows = k + 1 + (end_row ? 1 : 0);
  if (rows > kMaxSampleRows)
    throw InputError("the time step dt " + format_number(dt) + " s would give " + std::to_string(rows) +
                     " rows, more than " + std::to_string(kMaxSampleRows) + "; use a larger step");
  return rows;
}

std::vector<BoundsStage> BoundsTrajectory::sample(double dt) const {
  const long rows = sample_count(dt);
  std::vector<BoundsStage> out;
  out.reserve(static_cast<size_t>(rows));
  for (long i = 0; i < rows; ++i) {
    const double t = i == rows - 1 ? duration() : std::min(duration(), static_cast<double>(i) * dt);
    out.push_back(at_t(t));
  }
  return out;
}

bool BoundsTrajectory::contains(double s, const Eigen::VectorXd& q) const {
  if (q.size() != dof())
    throw InputError("a configuration of " + std::to_string(q.size()) + " values for bounds of " +
                     std::to_string(dof()) + " joints");
  const BoundsStage b = at_s(s);
  return (b.lower.array() <= q.array()).all() && (q.array() <= b.upper.array()).all();
}

}  // namespace leeway
