#pragma once
//! @file certify.hpp
//! Certified free regions of joint space: a conservative test that every configuration in a box
//! of joint values (or in the interpolated bounds between two waypoints) keeps every robot link
//! clear of every real obstacle and of the robot's other geoms (Scene::self_pairs()). Not a sample: a proof
//! by bounds. docs/algorithm.md ("Certified intervals") derives the bounds and the argument that makes each
//! conservative.

#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "leeway/core/box.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {

//! How the swept volume of a link over a joint box is bounded.
enum class CertifyBound {
  //! Per separating axis: the link's motion projected on the axis to first order through the
  //! Jacobian at the box centre, plus a sound second-order remainder (the default).
  kTaylor,
  //! The loose reference: the link's box inflated on every side by sum_i h_i rho_i, rho_i an
  //! upper bound of the distance from joint i's axis to the link's farthest corner.
  kLever,
};

//! Options of the certificate.
struct CertifyOptions {
  double margin = 0.001;    //!< required clearance [m]: a region is free when every link stays this far away
  long max_leaves = 16384;  //!< leaf budget of one region (or one segment); beyond it: not certified
  int max_depth = 40;       //!< deepest subdivision of one region
  CertifyBound bound = CertifyBound::kTaylor;
  //! The caller's work limit across calls: no call lets the CertifyStats it is given count more than
  //! this many leaves (probe checks included); a call that reaches it fails with `budget` set.
  long leaf_limit = std::numeric_limits<long>::max();
};

//! Counters of certification work.
struct CertifyStats {
  long leaves = 0;      //!< regions tested (each one kinematics pass and its pair tests)
  int max_depth = 0;    //!< deepest subdivision reached
  long pair_tests = 0;  //!< (link geom, obstacle) pairs tested
  void add(const CertifyStats& o);
};

//! Why a region was not certified: the first leaf that could not be proven free.
struct CertifyFailure {
  Eigen::VectorXd lower, upper;  //!< the leaf [rad or m]
  int link_geom = -1;            //!< the pair that could not be separated
  int obstacle_geom = -1;        //!< an obstacle, or the other robot geom when `self`
  bool self = false;             //!< the pair is two robot geoms (self-collision)
  int split_joint = -1;          //!< the joint whose motion contributes most to the failing pair
  bool budget = false;           //!< the leaf budget or depth ran out (rather than a leaf of width 0)
  //! The leaf's centre configuration itself comes within the margin of the obstacle: no
  //! subdivision can certify a region that contains it.
  bool centre_hits = false;
  double t0 = 0.0, t1 = 1.0;  //!< segment parameter range of the failing leaf (segments only)
  //! The leaf's worst pair: by how much the bound missed separating it [m] (<= 0; lower = worse).
  double gap = 0.0;
};

//! Proves joint-space regions free against the scene's obstacles and the robot itself. One object per thread
//! (it owns one mjData); the Scene must outlive it.
class Certifier {
 public:
  explicit Certifier(const Scene& scene, CertifyOptions options = {});

  //! True when every configuration q with lower <= q <= upper (per joint) is free: every link geom
  //! at least options.margin from every obstacle geom. Splits the box along the joint that
  //! contributes most to a failing pair, up to the leaf budget. `failure` (optional) describes the
  //! first leaf that could not be certified. @throws InputError on sizes, NaN, lower > upper.
  bool region_free(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, CertifyStats& stats,
                   CertifyFailure* failure = nullptr);

  //! True when every configuration of the segment between two bounded waypoints is free: for t in
  //! [0, 1] the joints range over [(1-t) lower_a + t lower_b, (1-t) upper_a + t upper_b] (the
  //! region leeway cf samples). [0, 1] is covered by sub-intervals, each enclosed by the box spanned
  //! by its end bounds, split where needed; one leaf budget for the whole segment.
  //! `proven` (optional) carries stretches [t0, t1] of the path parameter already proven free for
  //! bounds that contained these at every t (an earlier call before the bounds shrank): they are
  //! skipped, and the stretches this call proves are appended. The caller keeps it only while the
  //! bounds shrink.
  //! `grown_joint` (>= 0): the segment is a slab that grows a certified region in this joint only
  //! (at every t, joint grown_joint between the region's bound and the new one, the other joints
  //! within the region's bounds). A pair that this joint does not move is then apart over the slab
  //! because it is apart over the region (move the joint back to the region's bound: the pair's
  //! geometry is the same), so only the pairs it moves are proven. The caller vouches that the
  //! region is certified.
  bool segment_free(const Eigen::VectorXd& lower_a, const Eigen::VectorXd& upper_a,
                    const Eigen::VectorXd& lower_b, const Eigen::VectorXd& upper_b, CertifyStats& stats,
                    CertifyFailure* failure = nullptr,
                    std::vector<std::pair<double, double>>* proven = nullptr, int grown_joint = -1);

  //! A quick necessary test, not a proof: exact checks (the margin included) of the corners and
  //! centre of the bounds at t = 0, 1/4, 1/2, 3/4, 1 and of `samples` random configurations of the
  //! segment (a fixed, seeded sequence). False, with `failure` at the first configuration that comes
  //! within the margin of an obstacle (centre_hits set, t0 = t1 = its path parameter, split_joint =
  //! the joint whose offset from the nominal value qa..qb moves the failing link most).
  bool segment_probe(const Eigen::VectorXd& lower_a, const Eigen::VectorXd& upper_a,
                     const Eigen::VectorXd& lower_b, const Eigen::VectorXd& upper_b,
                     const Eigen::VectorXd& qa, const Eigen::VectorXd& qb, int samples, CertifyStats& stats,
                     CertifyFailure* failure = nullptr);

  //! One leaf, no subdivision: true when the bound proves the box free.
  bool leaf_free(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, CertifyStats& stats,
                 CertifyFailure* failure = nullptr);

  //! How many pairs each leaf proves: (link, obstacle) pairs and robot self pairs.
  int obstacle_pair_count() const { return obstacle_pairs_; }
  int self_pair_count() const { return static_cast<int>(self_pairs_.size()); }

  const CertifyOptions& options() const { return options_; }
  void set_options(const CertifyOptions& o) { options_ = o; }
  const Scene& scene() const { return *scene_; }

 private:
  struct Link {
    int geom = -1;
    std::vector<int> joints;    //!< robot joint indices that move this geom, base to tip
    std::vector<double> lever;  //!< per entry of `joints`: bound of |x - o_j| over all configurations [m]
    double corner_lever = 0.0;  //!< per joint bound of |corner - o_j| (the loose reference) [m]
  };
  //! A self pair: link `link` moves against robot geom `other_geom`. The link's first `shared`
  //! joints (those at or above the two geoms' deepest common body) are held at the leaf's centre;
  //! other_link (-1 when it does not move against the link's chain) likewise with other_shared.
  struct SelfPair {
    int link = -1;
    int shared = 0;
    int other_geom = -1;
    int other_link = -1;
    int other_shared = 0;
  };
  struct Obstacle {
    int geom = -1;
    Box box;
    bool plane = false;   //!< a half-space (normal = box z axis, surface through the centre)
    double radius = 0.0;  //!< bounding-sphere radius of the box (infinite for planes)
  };

  bool leaf_free_impl(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, std::vector<int>& pairs,
                      CertifyStats& stats, CertifyFailure* failure, const Eigen::VectorXd* blame = nullptr);
  //! `pairs`: the pairs to prove at the root (all_pairs_, or a slab's pairs_moved_by_).
  bool region_free_impl(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, CertifyStats& stats,
                        CertifyFailure* failure, long budget, const std::vector<int>& pairs);
  //! Exact tests of the box's centre and corners (random points when there are more than 256
  //! corners): false, with `failure` at the first point within the margin of an obstacle, when one
  //! is. Such a region can never be certified, however finely it is split.
  bool probe(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, const Eigen::VectorXd& nominal,
             CertifyStats& stats, CertifyFailure* failure);

  const Scene* scene_;
  CertifyOptions options_;
  RobotState state_;
  std::vector<Link> links_;
  std::vector<Obstacle> obstacles_;
  std::vector<bool> prismatic_;
  std::vector<SelfPair> self_pairs_;
  int obstacle_pairs_ = 0;  //!< pair indices below it are (link, obstacle), link-major; the rest self pairs
  std::vector<int> all_pairs_;  //!< every pair index
  //! Per robot joint: the pairs whose distance it can change (see segment_free's grown_joint).
  std::vector<std::vector<int>> pairs_moved_by_;
};

}  // namespace leeway
