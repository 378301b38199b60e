#pragma once
// The room measure's ceiling (docs/results.md, "Room: the ceiling"): boxes grown by sampling
// instead of proof, under the bounds file's contract or each waypoint alone. A study tool for the
// bench program leeway-bench-room-ceiling and its tests, not part of the library.
//
// Per waypoint the one-joint free ranges (measure_room's), then each side of each joint in turn,
// tip to base, every waypoint in turn, widens by a step of its free side's length (halved on a
// collision, down to 1/512 of it), in rounds until no side can grow. A box is accepted when none of
// its test configurations collides (RobotState::in_collision: the obstacles and the robot itself,
// no margin). Sampling misses thin collisions and the margin is not kept, so the estimate errs
// high; the greedy rule can miss better boxes, so it errs low.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "core/random.hpp"
#include "leeway/core/bounds.hpp"
#include "leeway/core/certify.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/room.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {

//! What each box test checks.
struct CeilingOptions {
  int samples = 400;       //!< random configurations per test (and per segment next to the waypoint)
  int slices = 8;          //!< segment contract: the corners at slices + 1 evenly spaced parameters
  std::uint64_t seed = 1;  //!< the tests' random streams
};

//! The extents of every side: per waypoint, lo[i] = q[i] - lower[i], hi[i] = upper[i] - q[i].
struct CeilingExtents {
  std::vector<Eigen::VectorXd> lo, hi;
};

//! What the certificate proves of a path's extents scaled toward the nominal values.
struct CeilingProof {
  double scale = 1.0;
  double share = 0.0;  //!< the scaled extents' mean share (RoomCeiling::mean_share)
  int segments = 0;    //!< segments of the file's contract (one on a one-waypoint path)
  int certified = 0;   //!< of them, proven free (Certifier::segment_free)
  long leaves = 0;     //!< the certificate's leaves, all segments
};

//! The ceiling of one path's room (waypoint or segment contract).
class RoomCeiling {
 public:
  //! Corners of an n-joint box are enumerated up to this many joints; above it, 256 random ones.
  static constexpr int kMaxCornerJoints = 8;
  //! A side's first step and its smallest, as shares of its free side's length.
  static constexpr double kFirstStep = 1.0 / 32;
  static constexpr double kLastStep = 1.0 / 512;

  RoomCeiling(const Scene& scene, std::vector<WaypointBounds> path, const CeilingOptions& o)
      : state_(scene), path_(std::move(path)), o_(o), n_(scene.dof()) {
    for (const auto& w : path_) free_.push_back(one_joint_free_ranges(state_, w.q, 1e-4));
  }

  //! The mean share of extents e, as measure_room computes it: per joint the mean over the
  //! waypoints of width / free width (where the free range is wider than the tolerance), then the
  //! mean over the joints.
  double mean_share(const CeilingExtents& e, Eigen::VectorXd* joint_share = nullptr) const {
    Eigen::VectorXd per = Eigen::VectorXd::Constant(n_, std::nan(""));
    double sum = 0;
    int joints = 0;
    for (int i = 0; i < n_; ++i) {
      double s = 0;
      int count = 0;
      for (size_t k = 0; k < path_.size(); ++k) {
        const double width = free_[k][i].upper - free_[k][i].lower;
        if (width <= 1e-4) continue;
        s += std::clamp((e.lo[k][i] + e.hi[k][i]) / width, 0.0, 1.0);
        ++count;
      }
      if (count == 0) continue;
      per[i] = s / count;
      sum += per[i];
      ++joints;
    }
    if (joint_share) *joint_share = per;
    return joints ? sum / joints : std::nan("");
  }

  //! The extents of the bounds the path came with (within the free ranges).
  CeilingExtents from_file() const {
    CeilingExtents e;
    for (size_t k = 0; k < path_.size(); ++k) {
      const auto& w = path_[k];
      e.lo.push_back((w.q - w.lower).cwiseMin(free_side(k, false)).cwiseMax(0.0));
      e.hi.push_back((w.upper - w.q).cwiseMin(free_side(k, true)).cwiseMax(0.0));
    }
    return e;
  }

  //! Zero extents: the nominal configurations.
  CeilingExtents zero() const {
    CeilingExtents e;
    for (size_t k = 0; k < path_.size(); ++k) {
      e.lo.push_back(Eigen::VectorXd::Zero(n_));
      e.hi.push_back(Eigen::VectorXd::Zero(n_));
    }
    return e;
  }

  //! Grows e side by side, tip to base, every waypoint in turn, until no side can grow.
  //! `segment`: the segment contract, else each waypoint alone.
  CeilingExtents grow(CeilingExtents e, bool segment) {
    struct Side {
      size_t k;
      int i;
      bool up;
      double step;
    };
    std::vector<Side> sides;
    for (size_t k = 0; k < path_.size(); ++k)
      for (int i = n_ - 1; i >= 0; --i)
        for (bool up : {false, true})
          if (free_side(k, up)[i] > 1e-4) sides.push_back({k, i, up, kFirstStep});
    bool any = true;
    while (any) {
      any = false;
      for (Side& s : sides) {
        const double room = free_side(s.k, s.up)[s.i];
        Eigen::VectorXd& ext = s.up ? e.hi[s.k] : e.lo[s.k];
        while (s.step >= kLastStep && ext[s.i] < room) {
          const double before = ext[s.i];
          ext[s.i] = std::min(room, before + s.step * room);
          if (free_at(e, s.k, segment)) {
            any = true;
            break;
          }
          ext[s.i] = before;
          s.step /= 2;
        }
      }
    }
    return e;
  }

  //! Random configurations along the whole path under the segment contract (the number of
  //! `count`, split evenly over the segments) that collide.
  long check(const CeilingExtents& e, int count) {
    std::mt19937_64 rng(detail::splitmix(o_.seed ^ 0xC4EC4ULL));
    long hits = 0;
    Eigen::VectorXd q(n_);
    const size_t segments = segment_count();
    for (size_t a = 0; a < segments; ++a) {
      const size_t b = segment_end(a);
      for (int j = 0; j < count / static_cast<int>(segments); ++j) {
        detail::draw_in_segment(lower(e, a), upper(e, a), lower(e, b), upper(e, b), detail::unit(rng), rng,
                                q);
        if (state_.in_collision(q)) ++hits;
      }
    }
    return hits;
  }

  //! Extents e with every side scaled by `scale` toward the nominal value, and each segment of the
  //! file's contract under them given to the certifier, on `leaves` leaves each: how much of the
  //! sampled room a proof keeps, and at what cost.
  CeilingProof certify(const CeilingExtents& e, double scale, long leaves, const Certifier& certifier,
                       CertifyContext& ctx) const {
    CeilingProof proof;
    proof.scale = scale;
    CeilingExtents scaled = e;
    for (size_t k = 0; k < path_.size(); ++k) {
      scaled.lo[k] *= scale;
      scaled.hi[k] *= scale;
    }
    proof.share = mean_share(scaled);
    for (size_t a = 0; a < segment_count(); ++a) {
      const size_t b = segment_end(a);
      CertifyStats stats;
      const bool free = certifier.segment_free(ctx, lower(scaled, a), upper(scaled, a), lower(scaled, b),
                                               upper(scaled, b), CertifyBudget{leaves}, stats);
      ++proof.segments;
      proof.certified += free ? 1 : 0;
      proof.leaves += stats.leaves;
    }
    return proof;
  }

  size_t waypoints() const { return path_.size(); }
  //! Waypoint k's one-joint free ranges.
  const std::vector<FreeRange>& free_ranges(size_t k) const { return free_[k]; }
  //! Waypoint k's bounds under extents e [rad or m].
  Eigen::VectorXd lower(const CeilingExtents& e, size_t k) const { return path_[k].q - e.lo[k]; }
  Eigen::VectorXd upper(const CeilingExtents& e, size_t k) const { return path_[k].q + e.hi[k]; }

 private:
  // The file's contract has a segment between each pair of neighbouring waypoints, and one (the
  // waypoint at both ends) on a one-waypoint path; segment a ends at waypoint segment_end(a).
  size_t segment_count() const { return path_.size() > 1 ? path_.size() - 1 : 1; }
  size_t segment_end(size_t a) const { return std::min(a + 1, path_.size() - 1); }

  Eigen::VectorXd free_side(size_t k, bool up) const {
    Eigen::VectorXd v(n_);
    for (int i = 0; i < n_; ++i)
      v[i] = up ? free_[k][i].upper - path_[k].q[i] : path_[k].q[i] - free_[k][i].lower;
    return v;
  }
  // The test of waypoint k's box: alone, or on the segments next to it.
  bool free_at(const CeilingExtents& e, size_t k, bool segment) {
    std::mt19937_64 rng(detail::splitmix(o_.seed ^ detail::splitmix(++tests_)));
    if (!segment || path_.size() == 1)
      return box_free(lower(e, k), upper(e, k), lower(e, k), upper(e, k), rng);
    if (k > 0 && !box_free(lower(e, k - 1), upper(e, k - 1), lower(e, k), upper(e, k), rng)) return false;
    if (k + 1 < path_.size() && !box_free(lower(e, k), upper(e, k), lower(e, k + 1), upper(e, k + 1), rng))
      return false;
    return true;
  }

  // Corners at slices + 1 parameters (or only at 0 when both ends are the same box), then samples.
  bool box_free(const Eigen::VectorXd& la, const Eigen::VectorXd& ua, const Eigen::VectorXd& lb,
                const Eigen::VectorXd& ub, std::mt19937_64& rng) {
    const bool same = la == lb && ua == ub;
    const int slices = same ? 0 : o_.slices;
    Eigen::VectorXd q(n_);
    const long corners = n_ <= kMaxCornerJoints ? (1L << n_) : 256;
    for (int s = 0; s <= slices; ++s) {
      const double t = slices ? static_cast<double>(s) / slices : 0.0;
      const Eigen::VectorXd lo = la + t * (lb - la), hi = ua + t * (ub - ua);
      for (long c = 0; c < corners; ++c) {
        for (int i = 0; i < n_; ++i) {
          const bool up = n_ <= kMaxCornerJoints ? ((c >> i) & 1) != 0 : detail::unit(rng) < 0.5;
          q[i] = up ? hi[i] : lo[i];
        }
        if (state_.in_collision(q)) return false;
      }
    }
    for (int j = 0; j < o_.samples; ++j) {
      detail::draw_in_segment(la, ua, lb, ub, same ? 0.0 : detail::unit(rng), rng, q);
      if (state_.in_collision(q)) return false;
    }
    return true;
  }

  RobotState state_;
  std::vector<WaypointBounds> path_;
  CeilingOptions o_;
  int n_;
  std::vector<std::vector<FreeRange>> free_;
  std::uint64_t tests_ = 0;
};

}  // namespace leeway
