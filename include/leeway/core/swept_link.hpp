#pragma once
//! @file swept_link.hpp
//! The certificate's parts (Certifier uses them on every leaf): the bound of the space one robot
//! link sweeps while the joints range over a box, the separating-axis test of that bound against
//! an obstacle, and the blame (which joint to split). docs/algorithm.md ("Certified intervals")
//! derives the bound and why each part is conservative.

#include <mujoco/mujoco.h>
#include <Eigen/Core>

#include <cstddef>
#include <vector>

#include "leeway/core/box.hpp"
#include "leeway/core/shape.hpp"

namespace leeway {

//! A robot geom and the chain of joints that moves it, with the lever data of the bound.
struct LinkChain {
  int geom = -1;
  std::vector<int> joints;     //!< robot joint indices that move this geom, base to tip
  std::vector<int> mj_joints;  //!< per entry: the MuJoCo joint id
  std::vector<bool> slide;     //!< per entry: a prismatic joint
  std::vector<double> lever;   //!< per entry: bound of |x - o_j| over all configurations [m]
  double corner_lever = 0.0;   //!< bound of |corner - x| of the geom's box [m]
  //! A mesh geom's hull in its own frame (computed once; `mesh` false for other types).
  bool mesh = false;
  HullExtent hull;
  //! A pivot box (body >= 0) instead of the geom's own box: a box fixed on `body`, the body of
  //! chain entry `frozen_from` (a hinge), that holds the geom at every value of that joint and of
  //! every later one. Entries from `frozen_from` on are then held at the leaf's centre: the box
  //! holds what they sweep. docs/algorithm.md ("Pivot boxes") gives the two kinds and why each holds.
  int body = -1;
  size_t frozen_from = 0;
  Eigen::Vector3d local_pos = Eigen::Vector3d::Zero();      //!< the box's centre in `body`'s frame [m]
  Eigen::Matrix3d local_rot = Eigen::Matrix3d::Identity();  //!< its axes in `body`'s frame
  Eigen::Vector3d half_size = Eigen::Vector3d::Zero();      //!< its half sizes [m]
  //! The box keeps the world's axes (it holds a ball, whose orientation does not matter): only its
  //! centre moves, so the bound has no terms for turning box axes.
  bool translate_only = false;
};

//! What a link is tested against: an obstacle (or another robot geom) by its real shape.
struct SweepObstacle {
  int geom = -1;
  Shape shape;          //!< the geom as MuJoCo collides it (a box when a self pair's geom is grown)
  Box box;              //!< the box that holds it (shape.box)
  bool plane = false;   //!< a half-space (normal = box z axis, surface through the centre)
  double radius = 0.0;  //!< radius of a ball about box.center that holds it (infinite for planes)
};

//! An obstacle of the certificate from a geom's shape.
SweepObstacle sweep_obstacle(int geom, const Shape& shape);

//! True when `box` grown by `grow` [m] on every side touches or overlaps the obstacle: a box by the
//! separating-axis test, a plane as the half-space below its surface (normal = its z axis).
bool touches(const Box& box, double grow, const Box& obstacle, bool plane);

//! The bound of the space a link sweeps over a joint box: the link's box at the box centre c, its
//! first-order motion through the Jacobian at c, and a sound second-order remainder. Built in two
//! steps, because most pairs are separated by the first: start() (a sphere about x(c), no
//! Jacobian) and build() (the Jacobian, the axes' derivatives, the remainder's terms).
//! Buffers keep their capacity across leaves: reuse one object per thread.
class SweptLink {
 public:
  //! A new leaf: forgets what start() cached for the previous one.
  void new_leaf() { cached_link_ = -1; }
  //! Starts the bound of `link` (index `link_id`, for the cache) over half-widths `h` (per robot
  //! joint) about the configuration of `d`, its first `held` joints held at the centre (and, for a
  //! pivot box, its entries from frozen_from on).
  void start(const LinkChain& link, int link_id, const Eigen::VectorXd& h, int held, const mjModel& m,
             const mjData& d);
  //! The link's box at the centre (it holds the link's shape; a pivot box is its own shape).
  const Box& box() const { return box_; }
  //! The link's shape at the centre: its geom's, or its box for a pivot box.
  const Shape& shape() const { return shape_; }
  //! True when the shape is not its box (a round or mesh link): extent() then uses the shape.
  bool shaped() const { return !shape_.is_box(); }
  //! How far the link's shape at the centre reaches along the unit axis n beyond its box's centre,
  //! max over its points y of n . (y - box().center) [m]: box_extent(n) for a box.
  //! `hint`: the mesh support's climbing hint (Shape::support_point).
  double extent(const Eigen::Vector3d& n, int* hint = nullptr) const;
  //! Radius of a sphere about the box's centre that holds the swept link (no Jacobian) [m].
  double cheap_radius() const { return iso_cheap_; }
  //! Builds the Jacobian-based bound (once per start()).
  void build();
  bool built() const { return built_; }
  //! After build(): a tighter sphere radius than cheap_radius() [m].
  double radius() const { return iso_; }
  //! After build(): the loose lever-arm reference's inflation sum_i h_i (lever_i + corner) [m].
  double lever_radius() const { return lever_radius_; }
  //! After build(): the first-order motion's half extent on the unit axis n: sum_p h_p (|n . J_p|
  //! + sum_k b_k |n . d e_k / d q_p|) [m].
  double motion_extent(const Eigen::Vector3d& n) const;
  //! The half extent of the link's box at the centre on the unit axis n [m].
  double box_extent(const Eigen::Vector3d& n) const;
  //! After build(): the remainder on n, bounded cheaply (every term's isotropic bound) [m].
  double remainder_cheap(const Eigen::Vector3d& n) const;
  //! After build(): the remainder on n, each term the smaller of its isotropic bound and its value
  //! at c plus its variation [m]; never above remainder_cheap(n).
  double remainder_refined(const Eigen::Vector3d& n);
  //! After build(): how far entry p of the chain, moving by w, moves the link along n (first order,
  //! plus its share of the remainder) [m]: the blame's measure.
  double contribution(const Eigen::Vector3d& n, size_t p, double w) const;
  const LinkChain& link() const { return *link_; }
  //! The half-widths with the held joints zeroed [rad or m].
  const Eigen::VectorXd& half_widths() const { return hl_; }
  int held() const { return held_; }

 private:
  // One second-order term (p, q) of the remainder.
  struct Term {
    size_t p = 0;
    double coef = 0, iso = 0, var = 0, var_e = 0;
    bool turns_axes = false;  // the term turns the box's axes (a hinge q, a box that turns)
    Eigen::Vector3d w = Eigen::Vector3d::Zero();
    Eigen::Matrix3d we = Eigen::Matrix3d::Zero();
  };
  void build_terms();
  double s_of(const Eigen::Vector3d& n, size_t p) const;

  const LinkChain* link_ = nullptr;
  const mjData* d_ = nullptr;
  int held_ = 0;
  Box box_;
  Shape shape_;
  Eigen::VectorXd hl_;
  bool built_ = false, terms_built_ = false;
  std::vector<Eigen::Vector3d> jac_;       // d x / d q_p at c
  std::vector<Eigen::Matrix3d> axis_jac_;  // column k: d e_k / d q_p at c
  std::vector<Eigen::Vector3d> axis_;      // joint axes at c
  std::vector<double> theta_before_;       // rotation the hinges before each joint can give its axis
  std::vector<double> dv_;                 // per joint q: |v_q(q) - v_q(c)|
  std::vector<double> r_pos_, r_rot_;      // per joint p: the remainder terms (p, q >= p)
  std::vector<Term> terms_;
  Eigen::VectorXd tail_held_;  // h with a pivot box's frozen entries zeroed
  // r_pos, r_rot and the isotropic terms of the link `cached_link_` with no joint held.
  std::vector<double> full_r_pos_, full_r_rot_, iso_term_;
  int cached_link_ = -1;
  double theta_ = 0;         // the rotation all the link's hinges can give
  double iso_ = 0;           // radius of a sphere around x(c) holding the swept link
  double iso_cheap_ = 0;     // a larger one, without the Jacobian
  double rem_iso_ = 0;       // the remainder's isotropic size
  double lever_radius_ = 0;  // the loose reference's inflation
  Eigen::Matrix3Xd motion_;  // the first-order motion's directions, scaled by the half-widths
  Eigen::Index motion_cols_ = 0;
};

//! The separating-axis test of a swept link against an obstacle, and the axis that came closest.
struct Separation {
  bool separated = false;
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();  //!< the best axis tried (unit)
  double gap = 0.0;  //!< on that axis: the clearance the bound leaves [m] (see separate())
};

//! Whether the swept link (built) stays more than `margin` from the obstacle: the sphere of
//! radius(), then the candidate axes (the obstacle's 3 face normals, the link box's 3, their 9
//! cross products, the centre line; a plane's normal only). When the link or the obstacle is not a
//! box, each side's projection is its shape's support, and the axis of the two shapes' closest
//! points at the centre (GJK) is tried first. `gap` is the best axis's clearance
//! under the bound, margin not subtracted (-infinity when no axis was tried).
Separation separate(SweptLink& link, const SweepObstacle& obstacle, double margin);

//! The joint (a robot joint index, -1 when none moves the link) whose motion by `weights` (per
//! robot joint, held joints ignored) moves the link most along `axis`: the one to split or shrink.
//! `bound` (optional) measures the motion instead of SweptLink::contribution.
class SweepBound;
int blame(const SweptLink& link, const Eigen::Vector3d& axis, const Eigen::VectorXd& weights,
          const SweepBound* bound = nullptr);

//! A replacement for the Taylor bound of one pair: tests and benchmarks compare the certificate
//! under other bounds through it (CertifyOptions::bound).
class SweepBound {
 public:
  virtual ~SweepBound() = default;
  //! True when the link swept over the leaf (built) stays more than `margin` from the obstacle.
  virtual bool separated(const SweptLink& link, const SweepObstacle& obstacle, double margin) const = 0;
  //! How much chain entry p, moving by w, moves the link: the blame's measure under this bound.
  virtual double contribution(const SweptLink& link, size_t p, double w) const = 0;
};

}  // namespace leeway
