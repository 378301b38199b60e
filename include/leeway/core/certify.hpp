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
#include "leeway/core/swept_link.hpp"

namespace leeway {

//! Options of the certificate, fixed for a Certifier's life.
struct CertifyOptions {
  double margin = 0.001;    //!< required clearance [m]: a region is free when every link stays this far away
  long max_leaves = 16384;  //!< the default leaf budget of one region (or one segment): Certifier::budget()
  int max_depth = 40;       //!< deepest subdivision of one region
  //! Another bound than the Taylor bound for every pair (tests and benchmarks compare the loose
  //! lever-arm reference through it); null: the Taylor bound. Not owned: it outlives the Certifier.
  const SweepBound* bound = nullptr;
  //! A pair the link's own bound cannot separate over a leaf is also tried with the link's pivot
  //! boxes (docs/algorithm.md, "Pivot boxes"): they make a wide wrist cheap to prove, and cost a
  //! leaf more where the wrist is narrow.
  bool pivot_boxes = true;
};

//! The work one call may do, passed to each call (never stored in the certifier).
struct CertifyBudget {
  long max_leaves = 16384;  //!< leaf budget of this region (or segment); beyond it: not certified
  //! The caller's work limit across calls: no call lets the CertifyStats it is given count more than
  //! this many leaves (probe checks included); a call that reaches it fails with `budget` set.
  long leaf_limit = std::numeric_limits<long>::max();
  //! Certifier::segment_free: when a stretch of the segment cannot be proven on a share of the
  //! budget, whether shorter stretches are tried (true) or the stretch gets the whole remaining
  //! budget for its joint splits (false: each shorter stretch proves the whole box of the other
  //! joints there again, which costs a thin growth slab more than it saves).
  bool split_path_on_failure = true;
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

//! The scratch one thread's certificate calls work in: one mjData (the robot at a leaf's centre)
//! and the buffers of the swept-link bound. Any Certifier of the same Scene can use it; one per
//! thread, and the Scene must outlive it.
class CertifyContext {
 public:
  explicit CertifyContext(const Scene& scene) : scene_(&scene), state_(scene) {}
  const Scene& scene() const { return *scene_; }

 private:
  friend class Certifier;
  const Scene* scene_;
  RobotState state_;
  SweptLink sweep_;
  SweptLink pivot_sweep_[2];                // a link's pivot boxes (at most two), and
  std::pair<int, int> pivot_last_[2] = {};  // which box and held count each was started for
  Eigen::VectorXd centre_, half_;
  std::vector<int> failing_;
};

//! Proves joint-space regions free against the scene's obstacles and the robot itself. Immutable
//! after construction (the cell's pairs and the links' lever data): threads share one and pass
//! each call their own CertifyContext. The Scene must outlive it.
class Certifier {
 public:
  explicit Certifier(const Scene& scene, CertifyOptions options = {});

  //! True when every configuration q with lower <= q <= upper (per joint) is free: every link geom
  //! at least options.margin from every obstacle geom. Splits the box along the joint that
  //! contributes most to a failing pair, up to the budget. `failure` (optional) describes the
  //! first leaf that could not be certified. @throws InputError on sizes, NaN, lower > upper.
  bool region_free(CertifyContext& ctx, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                   const CertifyBudget& budget, CertifyStats& stats, CertifyFailure* failure = nullptr) const;
  //! region_free with budget().
  bool region_free(CertifyContext& ctx, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                   CertifyStats& stats, CertifyFailure* failure = nullptr) const {
    return region_free(ctx, lower, upper, budget(), stats, failure);
  }

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
  bool segment_free(CertifyContext& ctx, const Eigen::VectorXd& lower_a, const Eigen::VectorXd& upper_a,
                    const Eigen::VectorXd& lower_b, const Eigen::VectorXd& upper_b,
                    const CertifyBudget& budget, CertifyStats& stats, CertifyFailure* failure = nullptr,
                    std::vector<std::pair<double, double>>* proven = nullptr, int grown_joint = -1) const;
  //! segment_free with budget().
  bool segment_free(CertifyContext& ctx, const Eigen::VectorXd& lower_a, const Eigen::VectorXd& upper_a,
                    const Eigen::VectorXd& lower_b, const Eigen::VectorXd& upper_b, CertifyStats& stats,
                    CertifyFailure* failure = nullptr,
                    std::vector<std::pair<double, double>>* proven = nullptr, int grown_joint = -1) const {
    return segment_free(ctx, lower_a, upper_a, lower_b, upper_b, budget(), stats, failure, proven,
                        grown_joint);
  }

  //! A quick necessary test, not a proof: exact checks (the margin included) of the corners and
  //! centre of the bounds at t = 0, 1/4, 1/2, 3/4, 1 and of `samples` random configurations of the
  //! segment (a fixed, seeded sequence). False, with `failure` at the first configuration that comes
  //! within the margin of an obstacle (centre_hits set, t0 = t1 = its path parameter, split_joint =
  //! the joint whose offset from the nominal value qa..qb moves the failing link most). Each check
  //! counts a leaf against `leaf_limit`. `grown_joint` (>= 0): the bounds are (a part of) a slab
  //! that grows a certified region in this joint only, as in segment_free, and only the pairs it
  //! moves are checked.
  bool segment_probe(CertifyContext& ctx, const Eigen::VectorXd& lower_a, const Eigen::VectorXd& upper_a,
                     const Eigen::VectorXd& lower_b, const Eigen::VectorXd& upper_b,
                     const Eigen::VectorXd& qa, const Eigen::VectorXd& qb, int samples, CertifyStats& stats,
                     CertifyFailure* failure = nullptr, long leaf_limit = std::numeric_limits<long>::max(),
                     int grown_joint = -1) const;

  //! A quick necessary test of a box, not a proof: exact checks (the margin included) of its corners
  //! (up to 256; beyond 8 moving joints a seeded choice of them) and its centre. `grown_joint` as in
  //! segment_probe. Each check counts a leaf against `leaf_limit`.
  bool box_probe(CertifyContext& ctx, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                 CertifyStats& stats, long leaf_limit = std::numeric_limits<long>::max(),
                 int grown_joint = -1) const;

  //! One leaf, no subdivision: true when the bound proves the box free.
  bool leaf_free(CertifyContext& ctx, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                 CertifyStats& stats, CertifyFailure* failure = nullptr) const;

  //! Whether a box's proof can hold joint `joint` at any width for the price of none: every robot
  //! geom the joint moves is fixed on the joint's body (the joint is the last on its chain), and
  //! the pivot cylinder about the joint holds it (docs/algorithm.md, "Pivot boxes"), which the
  //! certificate tries when the geom's own bound fails. False without pivot boxes (or with another
  //! bound), and for a joint that moves no geom. @throws InputError for a joint out of range.
  bool turns_last(int joint) const;

  //! How many pairs each leaf proves: (link, obstacle) pairs and robot self pairs.
  int obstacle_pair_count() const { return obstacle_pairs_; }
  int self_pair_count() const { return static_cast<int>(self_pairs_.size()); }

  const CertifyOptions& options() const { return options_; }
  //! The default budget: options().max_leaves per call, no limit across calls.
  CertifyBudget budget() const { return CertifyBudget{options_.max_leaves}; }
  const Scene& scene() const { return *scene_; }

 private:
  //! A self pair: link `link` moves against robot geom `other_geom`. The link's first `shared`
  //! joints (those at or above the two geoms' deepest common body) are held at the leaf's centre;
  //! other_link (-1 when it does not move against the link's chain) likewise with other_shared.
  struct SelfPair {
    int link = -1;
    int shared = 0;
    int other_geom = -1;
    int other_link = -1;
    int other_shared = 0;
    bool other_mesh = false;  // the other geom is a mesh: its hull's extent, computed once
    HullExtent other_hull;
  };

  void add_links(RobotState& state);
  void add_pivots(const RobotState& state, const LinkChain& link, const std::vector<int>& bodies,
                  const std::vector<int>& jids, const std::vector<size_t>& body_of_joint,
                  const std::vector<int>& robot_index);
  void add_self_pairs();
  void index_pairs();
  //! A self pair's other geom at the leaf's centre, grown by what its own free joints move it.
  SweepObstacle other_geom_swept(const CertifyContext& ctx, const SelfPair& pair,
                                 const Shape& at_centre) const;
  //! Fills `failure` for the leaf's first failing pair (the blame: the joint to split).
  void describe_failure(const CertifyContext& ctx, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                        const SweepObstacle& obs, bool self, const Separation& sep,
                        const Eigen::VectorXd* blame_weights, CertifyFailure& failure) const;
  bool pivot_separates(CertifyContext& ctx, int li, int held, const SweepObstacle& obs) const;
  bool leaf_free_impl(CertifyContext& ctx, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                      std::vector<int>& pairs, CertifyStats& stats, CertifyFailure* failure,
                      const Eigen::VectorXd* blame_weights = nullptr) const;
  //! `pairs`: the pairs to prove at the root (all_pairs_, or a slab's pairs_moved_by_).
  bool region_free_impl(CertifyContext& ctx, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                        CertifyStats& stats, CertifyFailure* failure, long max_leaves, long leaf_limit,
                        const std::vector<int>& pairs) const;
  //! Exact tests of the box's centre and corners (random points when there are more than 256
  //! corners): false, with `failure` at the first point within the margin of an obstacle, when one
  //! is. Such a region can never be certified, however finely it is split. `checked`: the pairs
  //! tested (null: all).
  bool probe(CertifyContext& ctx, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
             const Eigen::VectorXd& nominal, long leaf_limit, CertifyStats& stats, CertifyFailure* failure,
             const std::vector<int>* checked = nullptr) const;
  void check_context(const CertifyContext& ctx) const;
  // The pairs a slab that grows `grown_joint` must prove (all of them when it is negative).
  // @throws InputError when the robot has no such joint.
  const std::vector<int>& pairs_for(int grown_joint) const;

  const Scene* scene_;
  CertifyOptions options_;
  std::vector<LinkChain> links_;
  //! Pivot boxes (LinkChain::body >= 0), and per link the indices of its own: a pair its box
  //! cannot separate over a leaf is proven when one of them separates it.
  std::vector<LinkChain> pivots_;
  std::vector<std::vector<int>> pivots_of_;
  std::vector<SweepObstacle> obstacles_;
  std::vector<SelfPair> self_pairs_;
  int obstacle_pairs_ = 0;  //!< pair indices below it are (link, obstacle), link-major; the rest self pairs
  std::vector<int> all_pairs_;  //!< every pair index
  //! Per robot joint: the pairs whose distance it can change (see segment_free's grown_joint).
  std::vector<std::vector<int>> pairs_moved_by_;
};

}  // namespace leeway
