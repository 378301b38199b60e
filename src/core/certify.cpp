#include "leeway/core/certify.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <tuple>

#include "leeway/core/error.hpp"

namespace leeway {
namespace {

// A joint box being tested: its bounds, depth, and the pairs its parent could not separate (pairs
// separated over a box stay separated over every sub-box).
struct Cell {
  Eigen::VectorXd lower, upper;
  int depth = 0;
  std::vector<int> pairs;
  int split = -1;  // the joint to split next (set when the cell waits in the heap)
};

void check_box(const Scene& scene, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  if (lower.size() != scene.dof() || upper.size() != scene.dof())
    throw InputError("certify: a region needs " + std::to_string(scene.dof()) + " joint values per bound");
  for (int i = 0; i < scene.dof(); ++i)
    if (!std::isfinite(lower[i]) || !std::isfinite(upper[i]) || lower[i] > upper[i])
      throw InputError("certify: joint '" + scene.joints()[static_cast<size_t>(i)].name + "' bounds [" +
                       format_number(lower[i]) + ", " + format_number(upper[i]) +
                       "] are not finite or not ordered");
}

// The caller's leaf limit (CertifyOptions::leaf_limit) is reached: false, with `failure` saying
// that the region was not shown free for want of work (budget), not for a collision (no
// centre_hits, no pair).
bool out_of_leaves(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, CertifyFailure* failure) {
  if (failure) {
    *failure = CertifyFailure{};
    failure->lower = lower;
    failure->upper = upper;
    failure->budget = true;
  }
  return false;
}

// The bound of |x - o_j| over every configuration, for entry p of a chain of MuJoCo joints `jids`
// (bodies base to tip, body_of_joint[p] the index in `bodies` of joint p's body), by the triangle
// inequality over the offsets of the chain: the anchor's offset in its body, every later body's
// position in its parent, the shift of a body's origin by its own joints (a later hinge: at most
// twice its anchor offset; a later slide: its longest travel from the reference position within its
// limits) and x's offset `offset` in the last body. Rotations keep lengths. Only the first
// `joint_end` joints and `body_end` bodies count (x is fixed on bodies[body_end - 1]).
double chain_lever(const Scene& scene, const std::vector<int>& bodies, const std::vector<int>& jids,
                   const std::vector<size_t>& body_of_joint, const std::vector<int>& robot_index, size_t p,
                   size_t joint_end, size_t body_end, double offset) {
  const mjModel& m = scene.model();
  double lever = vec3(m.jnt_pos + 3 * jids[p]).norm();
  for (size_t q = p + 1; q < joint_end; ++q) {
    const int later = jids[q];
    lever += 2 * vec3(m.jnt_pos + 3 * later).norm();
    if (m.jnt_type[later] == mjJNT_SLIDE) {
      const double ref = m.qpos0[m.jnt_qposadr[later]];
      const auto& joint = scene.joints()[static_cast<size_t>(robot_index[static_cast<size_t>(later)])];
      lever += std::max(std::abs(joint.lower - ref), std::abs(joint.upper - ref));
    }
  }
  for (size_t k = body_of_joint[p] + 1; k < body_end; ++k) lever += vec3(m.body_pos + 3 * bodies[k]).norm();
  return lever + offset;
}

// Whether the sphere that holds the swept link without the Jacobian (SweptLink::cheap_radius) and
// the obstacle's bounding sphere are more than `margin` apart (never for a plane).
bool apart_by_spheres(const SweptLink& sweep, const SweepObstacle& obs, double margin) {
  return !obs.plane &&
         (obs.box.center - sweep.box().center).norm() - sweep.cheap_radius() - obs.radius > margin;
}

// Distance from point x to the line through o along unit a.
double line_distance(const Eigen::Vector3d& x, const Eigen::Vector3d& o, const Eigen::Vector3d& a) {
  const Eigen::Vector3d v = x - o;
  return (v - a.dot(v) * a).norm();
}

// The bodies from `body` up to the world (excluded), tip first.
std::vector<int> chain_of(const mjModel& m, int body) {
  std::vector<int> out;
  for (int b = body; b > 0; b = m.body_parentid[b]) out.push_back(b);
  return out;
}

}  // namespace

void CertifyStats::add(const CertifyStats& o) {
  leaves += o.leaves;
  max_depth = std::max(max_depth, o.max_depth);
  pair_tests += o.pair_tests;
}

Certifier::Certifier(const Scene& scene, CertifyOptions options) : scene_(&scene), options_(options) {
  RobotState state(scene);
  add_links(state);
  // Obstacles are static: their world boxes once.
  state.set(scene.lower_limits().cwiseMax(0).cwiseMin(scene.upper_limits()));
  const mjModel& m = scene.model();
  for (int g : scene.obstacle_geoms())
    obstacles_.push_back(sweep_obstacle(g, geom_shape(m, state.data(), g)));
  add_self_pairs();
  index_pairs();
}

void Certifier::add_links(RobotState& state) {
  const Scene& scene = *scene_;
  const mjModel& m = scene.model();
  std::vector<int> robot_index(static_cast<size_t>(m.njnt), -1);
  for (int i = 0; i < scene.dof(); ++i)
    robot_index[static_cast<size_t>(scene.joints()[static_cast<size_t>(i)].id)] = i;
  for (int g : scene.link_geoms()) {
    LinkChain link;
    link.geom = g;
    // The bodies from the geom's body up to the world, then reversed: base to tip.
    std::vector<int> bodies = chain_of(m, m.geom_bodyid[g]);
    std::reverse(bodies.begin(), bodies.end());
    // Joints in kinematic order (within a body, in model order, as mj_kinematics applies them).
    std::vector<int> jids;
    std::vector<size_t> body_of_joint;  // index into `bodies`
    for (size_t k = 0; k < bodies.size(); ++k)
      for (int jj = 0; jj < m.body_jntnum[bodies[k]]; ++jj) {
        jids.push_back(m.body_jntadr[bodies[k]] + jj);
        body_of_joint.push_back(k);
      }
    const Box b0 = geom_box(m, state.data(), g);
    // The box's centre is the point x of the bound; a mesh's box is centred off the geom's origin.
    const double offset =
        vec3(m.geom_pos + 3 * g).norm() + (b0.center - vec3(state.data().geom_xpos + 3 * g)).norm();
    for (size_t p = 0; p < jids.size(); ++p) {
      const int r = robot_index[static_cast<size_t>(jids[p])];
      LEEWAY_DEMAND(r >= 0);  // the scene recognises every joint on a link's chain as a robot joint
      link.joints.push_back(r);
      link.mj_joints.push_back(jids[p]);
      link.slide.push_back(scene.joints()[static_cast<size_t>(r)].prismatic);
      link.lever.push_back(chain_lever(scene, bodies, jids, body_of_joint, robot_index, p, jids.size(),
                                       bodies.size(), offset));
    }
    link.corner_lever = std::isfinite(b0.half_size.norm()) ? b0.half_size.norm() : 0.0;
    link.mesh = m.geom_type[g] == mjGEOM_MESH;
    if (link.mesh) link.hull = hull_extent(m, g);
    pivots_of_.emplace_back();
    if (std::isfinite(link.corner_lever)) add_pivots(state, link, bodies, jids, body_of_joint, robot_index);
    links_.push_back(std::move(link));
  }
}

// Pivot boxes of a link (docs/algorithm.md, "Pivot boxes"), at the reference configuration of
// `state`: a box on the last hinge's body that holds the cylinder the geom sweeps about that hinge,
// and a cube about the point where a hinge's axis meets every later hinge's (a spherical wrist),
// which holds the ball the geom stays in whatever those joints do.
void Certifier::add_pivots(const RobotState& state, const LinkChain& link, const std::vector<int>& bodies,
                           const std::vector<int>& jids, const std::vector<size_t>& body_of_joint,
                           const std::vector<int>& robot_index) {
  const mjModel& m = scene_->model();
  const mjData& d = state.data();
  const size_t n = jids.size();
  const std::array<Eigen::Vector3d, 8> corners = box_corners(geom_box(m, d, link.geom));
  auto frame_of = [&](int body) { return mat3(d.xmat + 9 * body); };
  // A hinge that is its body's only joint: the body's frame turns about it and nothing else.
  auto pivot_hinge = [&](size_t k) {
    return m.jnt_type[jids[k]] == mjJNT_HINGE && m.body_jntnum[m.jnt_bodyid[jids[k]]] == 1;
  };
  auto add = [&](size_t k, const Eigen::Vector3d& centre, const Eigen::Matrix3d& axes,
                 const Eigen::Vector3d& half, bool translate_only) {
    LinkChain pivot = link;
    const int body = m.jnt_bodyid[jids[k]];
    pivot.body = body;
    pivot.frozen_from = k;
    pivot.local_pos = frame_of(body).transpose() * (centre - vec3(d.xpos + 3 * body));
    pivot.local_rot = frame_of(body).transpose() * axes;
    pivot.half_size = half;
    pivot.translate_only = translate_only;
    pivot.corner_lever = half.norm();
    for (size_t p = 0; p < k; ++p)
      pivot.lever[p] = chain_lever(*scene_, bodies, jids, body_of_joint, robot_index, p, k + 1,
                                   body_of_joint[k] + 1, pivot.local_pos.norm());
    pivots_of_.back().push_back(static_cast<int>(pivots_.size()));
    pivots_.push_back(std::move(pivot));
  };
  // The cylinder about the last hinge: the geom is fixed in that hinge's body.
  if (n > 0 && pivot_hinge(n - 1)) {
    const size_t k = n - 1;
    const Eigen::Vector3d a = vec3(d.xaxis + 3 * jids[k]).normalized();
    const Eigen::Vector3d o = vec3(d.xanchor + 3 * jids[k]);
    double zmin = INFINITY, zmax = -INFINITY, radial = 0;
    for (const Eigen::Vector3d& c : corners) {
      const double z = a.dot(c - o);
      zmin = std::min(zmin, z);
      zmax = std::max(zmax, z);
      radial = std::max(radial, line_distance(c, o, a));
    }
    Eigen::Matrix3d axes;
    axes.col(0) = a;
    axes.col(1) = a.unitOrthogonal();
    axes.col(2) = a.cross(axes.col(1));
    add(k, o + a * (zmin + zmax) / 2, axes, Eigen::Vector3d((zmax - zmin) / 2, radial, radial), false);
  }
  // The ball about a spherical wrist: the most proximal hinge k whose axis meets the next one's at a
  // point P that lies on every later axis, all of them hinges. Every later rotation keeps P fixed,
  // so each point of the geom stays at its distance from P. (A turn about an axis that misses P by d
  // moves a point at most 2 d further from P: axes that miss it by more than a nanometre in all are
  // not used, and 1 micrometre, far more than the rounding and such misses can add, goes on the
  // radius.)
  for (size_t k = 0; k + 1 < n; ++k) {
    bool hinges = pivot_hinge(k);
    for (size_t j = k + 1; j < n && hinges; ++j) hinges = m.jnt_type[jids[j]] == mjJNT_HINGE;
    if (!hinges) continue;
    const Eigen::Vector3d a = vec3(d.xaxis + 3 * jids[k]).normalized(), o = vec3(d.xanchor + 3 * jids[k]);
    const Eigen::Vector3d b = vec3(d.xaxis + 3 * jids[k + 1]).normalized(),
                          ob = vec3(d.xanchor + 3 * jids[k + 1]);
    const double sine = a.cross(b).norm();
    if (sine < 1e-6) continue;
    // The point of axis k nearest to axis k + 1.
    const Eigen::Vector3d w = o - ob;
    const double ab = a.dot(b), s = (ab * b.dot(w) - a.dot(w)) / (1 - ab * ab);
    const Eigen::Vector3d centre = o + s * a;
    double miss = 0;
    for (size_t j = k + 1; j < n; ++j)
      miss += line_distance(centre, vec3(d.xanchor + 3 * jids[j]), vec3(d.xaxis + 3 * jids[j]).normalized());
    if (miss > 1e-9) continue;
    double radius = 0;
    for (const Eigen::Vector3d& c : corners) radius = std::max(radius, (c - centre).norm());
    radius += 1e-6;
    add(k, centre, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Constant(radius), true);
    break;
  }
}

// Self pairs: the geom on the later part moves against the other (docs/algorithm.md,
// "Self-collision"). `shared` counts the link's joints at or above the two geoms' deepest common
// body: they move both geoms rigidly, so they do not change the pair's distance.
void Certifier::add_self_pairs() {
  const Scene& scene = *scene_;
  const mjModel& m = scene.model();
  std::vector<int> link_of(static_cast<size_t>(m.ngeom), -1);
  for (size_t i = 0; i < links_.size(); ++i)
    link_of[static_cast<size_t>(links_[i].geom)] = static_cast<int>(i);
  auto shared_joints = [&](const LinkChain& link, const std::vector<int>& common) {
    int n = 0;
    for (int jid : link.mj_joints)
      if (std::find(common.begin(), common.end(), m.jnt_bodyid[jid]) != common.end()) ++n;
    return n;
  };
  for (const RobotPair& rp : scene.self_pairs()) {
    const std::vector<int> c1 = chain_of(m, m.geom_bodyid[rp.geom1]),
                           c2 = chain_of(m, m.geom_bodyid[rp.geom2]);
    std::vector<int> common;  // the deepest common body and its ancestors
    for (int b : c2)
      if (std::find(c1.begin(), c1.end(), b) != c1.end()) common.push_back(b);
    SelfPair sp;
    sp.link = link_of[static_cast<size_t>(rp.geom2)];
    LEEWAY_DEMAND(sp.link >= 0);  // the later part moves with a joint: its geom is a link
    sp.shared = shared_joints(links_[static_cast<size_t>(sp.link)], common);
    sp.other_geom = rp.geom1;
    sp.other_link = link_of[static_cast<size_t>(rp.geom1)];
    sp.other_mesh = m.geom_type[rp.geom1] == mjGEOM_MESH;
    if (sp.other_mesh) sp.other_hull = hull_extent(m, rp.geom1);
    if (sp.other_link >= 0) {
      const LinkChain& ol = links_[static_cast<size_t>(sp.other_link)];
      sp.other_shared = shared_joints(ol, common);
      if (sp.other_shared == static_cast<int>(ol.joints.size())) sp.other_link = -1;  // on the chain: still
    }
    self_pairs_.push_back(sp);
  }
  // Grouped by link and shared joints, so that a leaf builds each link's bound once per group.
  std::stable_sort(self_pairs_.begin(), self_pairs_.end(), [](const SelfPair& a, const SelfPair& b) {
    return std::tie(a.link, a.shared) < std::tie(b.link, b.shared);
  });
}

// Pair indices, and the joints each pair depends on: a link's chain against an obstacle; for a
// self pair, the joints below the two geoms' deepest common body.
void Certifier::index_pairs() {
  const int dof = scene_->dof();
  obstacle_pairs_ = static_cast<int>(links_.size() * obstacles_.size());
  all_pairs_.resize(static_cast<size_t>(obstacle_pairs_) + self_pairs_.size());
  for (size_t i = 0; i < all_pairs_.size(); ++i) all_pairs_[i] = static_cast<int>(i);
  pairs_moved_by_.assign(static_cast<size_t>(dof), {});
  for (int pair : all_pairs_) {
    std::vector<bool> moves(static_cast<size_t>(dof), false);
    if (pair < obstacle_pairs_) {
      for (int r : links_[static_cast<size_t>(pair / static_cast<int>(obstacles_.size()))].joints)
        moves[static_cast<size_t>(r)] = true;
    } else {
      const SelfPair& sp = self_pairs_[static_cast<size_t>(pair - obstacle_pairs_)];
      const auto& own = links_[static_cast<size_t>(sp.link)].joints;
      for (size_t p = static_cast<size_t>(sp.shared); p < own.size(); ++p)
        moves[static_cast<size_t>(own[p])] = true;
      if (sp.other_link >= 0) {
        const auto& other = links_[static_cast<size_t>(sp.other_link)].joints;
        for (size_t p = static_cast<size_t>(sp.other_shared); p < other.size(); ++p)
          moves[static_cast<size_t>(other[p])] = true;
      }
    }
    for (int r = 0; r < dof; ++r)
      if (moves[static_cast<size_t>(r)]) pairs_moved_by_[static_cast<size_t>(r)].push_back(pair);
  }
}

void Certifier::check_context(const CertifyContext& ctx) const {
  if (&ctx.scene() != scene_) throw InputError("certify: the context belongs to another scene");
}

bool Certifier::leaf_free(CertifyContext& ctx, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                          CertifyStats& stats, CertifyFailure* failure) const {
  check_context(ctx);
  check_box(*scene_, lower, upper);
  std::vector<int> pairs = all_pairs_;
  return leaf_free_impl(ctx, lower, upper, pairs, stats, failure);
}

// The distance between two robot geoms does not depend on the joints above their common ancestor
// (they move both rigidly), so those joints are held at the centre: the other geom stands at its
// pose there, grown by what the joints below the common ancestor can move it (a sound isotropic
// bound; zero on one chain, where the other geom is the ancestor's). docs/algorithm.md
// ("Self-collision") has the argument.
SweepObstacle Certifier::other_geom_swept(const CertifyContext& ctx, const SelfPair& pair,
                                          const Shape& at_centre) const {
  SweepObstacle other = sweep_obstacle(pair.other_geom, at_centre);
  double grow = 0;
  if (pair.other_link >= 0) {
    const LinkChain& ol = links_[static_cast<size_t>(pair.other_link)];
    for (size_t p = static_cast<size_t>(pair.other_shared); p < ol.joints.size(); ++p)
      grow += ctx.half_[ol.joints[p]] * (ol.slide[p] ? 1.0 : ol.lever[p] + ol.corner_lever);
  }
  if (grow == 0) return other;  // on one chain: the geom as it is
  other.box.half_size.array() += grow;
  other.shape = box_shape(other.box);
  other.radius = other.box.half_size.norm();
  return other;
}

// The blame: the joint whose motion moves the link most along the axis that came closest to
// separating the pair (first order, plus its share of the remainder); it is the one to split or
// shrink. Weights: the half-widths, or `blame_weights` when given (a probe's offsets).
void Certifier::describe_failure(const CertifyContext& ctx, const Eigen::VectorXd& lower,
                                 const Eigen::VectorXd& upper, const SweepObstacle& obs, bool self,
                                 const Separation& sep, const Eigen::VectorXd* blame_weights,
                                 CertifyFailure& failure) const {
  const SweptLink& sweep = ctx.sweep_;
  failure.lower = lower;
  failure.upper = upper;
  failure.link_geom = sweep.link().geom;
  failure.obstacle_geom = obs.geom;
  failure.self = self;
  failure.split_joint =
      blame(sweep, sep.axis, blame_weights ? *blame_weights : sweep.half_widths(), options_.bound);
  failure.budget = false;
}

// Whether one of link li's pivot boxes, swept over the leaf (its first `held` joints held, as the
// link's own bound), stays more than the margin from `obs`: then so does the link.
bool Certifier::pivot_separates(CertifyContext& ctx, int li, int held, const SweepObstacle& obs) const {
  const mjModel& m = scene_->model();
  const mjData& d = ctx.state_.data();
  const std::vector<int>& mine = pivots_of_[static_cast<size_t>(li)];
  for (size_t slot = 0; slot < mine.size(); ++slot) {
    const int v = mine[slot];
    const LinkChain& pivot = pivots_[static_cast<size_t>(v)];
    SweptLink& sweep = ctx.pivot_sweep_[slot];
    auto& [last_v, last_held] = ctx.pivot_last_[slot];
    if (last_v != v || last_held != held) {
      last_v = v;
      last_held = held;
      sweep.start(pivot, v, ctx.half_, held, m, d);
    }
    if (apart_by_spheres(sweep, obs, options_.margin)) return true;
    sweep.build();
    if (separate(sweep, obs, options_.margin).separated) return true;
  }
  return false;
}

// One leaf: every pair in `pairs` is tested at the box's centre c with half-widths h; on return
// `pairs` holds the pairs that could not be separated (empty: the box is free). Every pair is
// tested, not only up to the first failing one: the worst-first order needs the worst gap.
bool Certifier::leaf_free_impl(CertifyContext& ctx, const Eigen::VectorXd& lower,
                               const Eigen::VectorXd& upper, std::vector<int>& pairs, CertifyStats& stats,
                               CertifyFailure* failure, const Eigen::VectorXd* blame_weights) const {
  ++stats.leaves;
  ctx.centre_ = (lower + upper) / 2;
  ctx.half_ = (upper - lower) / 2;
  ctx.state_.set(ctx.centre_);
  const mjModel& m = scene_->model();
  const mjData& d = ctx.state_.data();
  const double margin = options_.margin;
  const size_t nobs = obstacles_.size();
  SweptLink& sweep = ctx.sweep_;
  sweep.new_leaf();
  for (size_t slot = 0; slot < 2; ++slot) {
    ctx.pivot_sweep_[slot].new_leaf();
    ctx.pivot_last_[slot] = {-1, 0};
  }
  ctx.failing_.clear();
  int last_link = -1, last_held = 0;
  if (failure) {
    failure->centre_hits = false;
    failure->gap = 0.0;
  }
  SweepObstacle other;  // a self pair's other robot geom, grown by its own motion
  Shape other_at_c;     // ... and as it is at c, for the centre test
  for (int pair : pairs) {
    ++stats.pair_tests;
    // An obstacle pair (link, obstacle), or a self pair: the link against another robot geom, the
    // joints above their common ancestor held at c.
    const bool self = pair >= obstacle_pairs_;
    const SelfPair* pair_info = self ? &self_pairs_[static_cast<size_t>(pair - obstacle_pairs_)] : nullptr;
    const int li = self ? pair_info->link : pair / static_cast<int>(nobs);
    const int held = self ? pair_info->shared : 0;
    if (self) {
      other_at_c =
          geom_shape(m, d, pair_info->other_geom, pair_info->other_mesh ? &pair_info->other_hull : nullptr);
      other = other_geom_swept(ctx, *pair_info, other_at_c);
    }
    const SweepObstacle& obs = self ? other : obstacles_[static_cast<size_t>(pair) % nobs];
    if (li != last_link || held != last_held) {
      last_link = li;
      last_held = held;
      sweep.start(links_[static_cast<size_t>(li)], li, ctx.half_, held, m, d);
    }
    // Most pairs are apart by more than the sphere that holds the swept link without the Jacobian.
    if (!options_.bound && apart_by_spheres(sweep, obs, margin)) continue;
    sweep.build();
    Separation sep;
    if (options_.bound) {
      sep.separated = options_.bound->separated(sweep, obs, margin);
      sep.axis = (obs.box.center - sweep.box().center).normalized();
      sep.gap = -std::numeric_limits<double>::infinity();
    } else {
      sep = separate(sweep, obs, margin);
    }
    if (sep.separated) continue;
    if (options_.pivot_boxes && !options_.bound && pivot_separates(ctx, li, held, obs)) continue;
    if (failure) {
      failure->gap = std::min(failure->gap, std::isfinite(sep.gap) ? sep.gap - margin : -1e9);
      if (ctx.failing_.empty()) describe_failure(ctx, lower, upper, obs, self, sep, blame_weights, *failure);
      // Does the centre configuration itself come within the margin? Then no split can help.
      if (!failure->centre_hits) {
        const Shape& at_c = self ? other_at_c : obs.shape;
        failure->centre_hits = sweep.shaped() || !(at_c.is_box() || at_c.plane())
                                   ? shape_distance(sweep.shape(), at_c) <= margin
                                   : touches(sweep.box(), margin, at_c.box, at_c.plane());
      }
    }
    ctx.failing_.push_back(pair);
  }
  pairs.swap(ctx.failing_);
  return pairs.empty();
}

bool Certifier::region_free_impl(CertifyContext& ctx, const Eigen::VectorXd& lower,
                                 const Eigen::VectorXd& upper, CertifyStats& stats, CertifyFailure* failure,
                                 long max_leaves, long leaf_limit, const std::vector<int>& pairs) const {
  // Worst-first refinement: the failing leaf whose bound misses by most is split first, so a region
  // that cannot be certified within max_depth fails after about 2 max_depth leaves instead of after
  // certifying everything around its hard spot; a free region costs the same as any order.
  const long start = stats.leaves;
  CertifyFailure local;
  auto worse = [](const std::pair<double, Cell>& x, const std::pair<double, Cell>& y) {
    return x.first > y.first;
  };
  std::vector<std::pair<double, Cell>> heap;
  auto test = [&](Cell cell) {
    stats.max_depth = std::max(stats.max_depth, cell.depth);
    if (leaf_free_impl(ctx, cell.lower, cell.upper, cell.pairs, stats, &local)) return true;
    const bool exhausted =
        stats.leaves - start >= max_leaves || stats.leaves >= leaf_limit || cell.depth >= options_.max_depth;
    if (local.split_joint < 0 || exhausted || local.centre_hits) {
      local.budget = exhausted && local.split_joint >= 0;
      if (failure) *failure = local;
      return false;
    }
    const double key = local.gap;
    cell.split = local.split_joint;
    heap.emplace_back(key, std::move(cell));
    std::push_heap(heap.begin(), heap.end(), worse);
    return true;
  };
  if (stats.leaves >= leaf_limit) return out_of_leaves(lower, upper, failure);
  Cell root{lower, upper, 0, {}};
  root.pairs = pairs;
  if (!test(std::move(root))) return false;
  while (!heap.empty()) {
    std::pop_heap(heap.begin(), heap.end(), worse);
    Cell cell = std::move(heap.back().second);
    heap.pop_back();
    const int j = cell.split;
    const double mid = (cell.lower[j] + cell.upper[j]) / 2;
    Cell a{cell.lower, cell.upper, cell.depth + 1, cell.pairs};
    Cell b{cell.lower, cell.upper, cell.depth + 1, std::move(cell.pairs)};
    a.upper[j] = mid;
    b.lower[j] = mid;
    if (!test(std::move(a)) || !test(std::move(b))) return false;
  }
  return true;
}

bool Certifier::probe(CertifyContext& ctx, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                      const Eigen::VectorXd& nominal, long leaf_limit, CertifyStats& stats,
                      CertifyFailure* failure, const std::vector<int>* checked) const {
  const int n = static_cast<int>(lower.size());
  std::vector<int> moving;
  for (int i = 0; i < n; ++i)
    if (upper[i] > lower[i]) moving.push_back(i);
  const std::uint64_t corners = moving.empty()       ? 0
                                : moving.size() <= 8 ? (std::uint64_t{1} << moving.size())
                                                     : 256;
  std::uint64_t state = 0x9E3779B97F4A7C15ULL;  // fixed sequence: deterministic
  Eigen::VectorXd p(n);
  CertifyFailure local;
  for (std::uint64_t k = 0; k <= corners; ++k) {
    p = (lower + upper) / 2;
    if (k < corners) {
      std::uint64_t bits = k;
      if (moving.size() > 8) {
        state = state * 6364136223846793005ULL + 1442695040888963407ULL;
        bits = state >> 11;
      }
      for (size_t m = 0; m < moving.size(); ++m)
        p[moving[m]] = (bits >> m) & 1 ? upper[moving[m]] : lower[moving[m]];
    }
    if (stats.leaves >= leaf_limit) return out_of_leaves(lower, upper, failure);
    std::vector<int> pairs = checked ? *checked : all_pairs_;
    const Eigen::VectorXd offsets = (p - nominal).cwiseAbs();
    if (leaf_free_impl(ctx, p, p, pairs, stats, &local, &offsets)) continue;
    local.centre_hits = true;
    if (failure) *failure = local;
    return false;
  }
  return true;
}

bool Certifier::turns_last(int joint) const {
  if (joint < 0 || joint >= scene_->dof()) throw InputError("certify: no joint " + std::to_string(joint));
  if (!options_.pivot_boxes || options_.bound) return false;
  bool moves_any = false;
  for (size_t li = 0; li < links_.size(); ++li) {
    const std::vector<int>& joints = links_[li].joints;
    const auto it = std::find(joints.begin(), joints.end(), joint);
    if (it == joints.end()) continue;
    moves_any = true;
    const size_t p = static_cast<size_t>(it - joints.begin());
    if (p + 1 != joints.size()) return false;
    const std::vector<int>& mine = pivots_of_[li];
    const bool cylinder = std::any_of(
        mine.begin(), mine.end(), [&](int v) { return pivots_[static_cast<size_t>(v)].frozen_from == p; });
    if (!cylinder) return false;
  }
  return moves_any;
}

const std::vector<int>& Certifier::pairs_for(int grown_joint) const {
  if (grown_joint >= scene_->dof()) throw InputError("certify: no joint " + std::to_string(grown_joint));
  return grown_joint < 0 ? all_pairs_ : pairs_moved_by_[static_cast<size_t>(grown_joint)];
}

bool Certifier::segment_probe(CertifyContext& ctx, const Eigen::VectorXd& lower_a,
                              const Eigen::VectorXd& upper_a, const Eigen::VectorXd& lower_b,
                              const Eigen::VectorXd& upper_b, const Eigen::VectorXd& qa,
                              const Eigen::VectorXd& qb, int samples, CertifyStats& stats,
                              CertifyFailure* failure, long leaf_limit, int grown_joint) const {
  check_context(ctx);
  check_box(*scene_, qa, qa);
  check_box(*scene_, qb, qb);
  check_box(*scene_, lower_a, upper_a);
  check_box(*scene_, lower_b, upper_b);
  const std::vector<int>& pairs = pairs_for(grown_joint);
  CertifyFailure local;
  for (double t : {0.0, 1.0, 0.5, 0.25, 0.75}) {
    if (probe(ctx, (1 - t) * lower_a + t * lower_b, (1 - t) * upper_a + t * upper_b, (1 - t) * qa + t * qb,
              leaf_limit, stats, &local, &pairs))
      continue;
    local.t0 = local.t1 = t;
    if (failure) *failure = local;
    return false;
  }
  std::uint64_t state = 0x2545F4914F6CDD1DULL;  // fixed sequence: deterministic
  auto unit = [&state] {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) * 0x1.0p-53;
  };
  const int n = scene_->dof();
  Eigen::VectorXd p(n);
  for (int k = 0; k < samples; ++k) {
    const double t = unit();
    const Eigen::VectorXd lo = (1 - t) * lower_a + t * lower_b, hi = (1 - t) * upper_a + t * upper_b;
    for (int i = 0; i < n; ++i) p[i] = lo[i] + (hi[i] - lo[i]) * unit();
    const Eigen::VectorXd nominal = (1 - t) * qa + t * qb;
    if (probe(ctx, p, p, nominal, leaf_limit, stats, &local, &pairs)) continue;
    local.t0 = local.t1 = t;
    if (failure) *failure = local;
    return false;
  }
  return true;
}

bool Certifier::box_probe(CertifyContext& ctx, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                          CertifyStats& stats, long leaf_limit, int grown_joint) const {
  check_context(ctx);
  check_box(*scene_, lower, upper);
  const std::vector<int>& pairs = pairs_for(grown_joint);
  return probe(ctx, lower, upper, (lower + upper) / 2, leaf_limit, stats, nullptr, &pairs);
}

bool Certifier::region_free(CertifyContext& ctx, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                            const CertifyBudget& budget, CertifyStats& stats, CertifyFailure* failure) const {
  check_context(ctx);
  check_box(*scene_, lower, upper);
  if (!probe(ctx, lower, upper, (lower + upper) / 2, budget.leaf_limit, stats, failure)) return false;
  return region_free_impl(ctx, lower, upper, stats, failure, budget.max_leaves, budget.leaf_limit,
                          all_pairs_);
}

bool Certifier::segment_free(CertifyContext& ctx, const Eigen::VectorXd& lower_a,
                             const Eigen::VectorXd& upper_a, const Eigen::VectorXd& lower_b,
                             const Eigen::VectorXd& upper_b, const CertifyBudget& budget, CertifyStats& stats,
                             CertifyFailure* failure, std::vector<std::pair<double, double>>* proven,
                             int grown_joint) const {
  check_context(ctx);
  check_box(*scene_, lower_a, upper_a);
  check_box(*scene_, lower_b, upper_b);
  const std::vector<int>& pairs = pairs_for(grown_joint);
  constexpr double kMinDt = 1.0 / (1 << 20);
  const long start = stats.leaves;
  std::vector<std::pair<double, double>> stack = {{0.0, 1.0}};
  auto known = [&](double t0, double t1) {
    if (!proven) return false;
    for (const auto& [p0, p1] : *proven)
      if (p0 <= t0 && t1 <= p1) return true;
    return false;
  };
  while (!stack.empty()) {
    const auto [t0, t1] = stack.back();
    stack.pop_back();
    if (known(t0, t1)) continue;  // a superset of this stretch was proven before
    const Eigen::VectorXd lo0 = (1 - t0) * lower_a + t0 * lower_b, lo1 = (1 - t1) * lower_a + t1 * lower_b;
    const Eigen::VectorXd hi0 = (1 - t0) * upper_a + t0 * upper_b, hi1 = (1 - t1) * upper_a + t1 * upper_b;
    // lower(t) and upper(t) are linear in t: over [t0, t1] they stay within their end values.
    const Eigen::VectorXd lo = lo0.cwiseMin(lo1), hi = hi0.cwiseMax(hi1);
    const bool splittable = t1 - t0 > kMinDt;
    // Split the path parameter first while the path's own motion over [t0, t1] dominates the box:
    // the hull of a long diagonal stretch is mostly empty space that no configuration visits.
    const Eigen::VectorXd motion = ((lo1 + hi1) - (lo0 + hi0)).cwiseAbs() / 2;
    const Eigen::VectorXd half = ((hi0 - lo0).cwiseMin(hi1 - lo1)) / 2;
    // (An absolute floor keeps zero-width bounds, whose box is the path's own motion, from being
    // split without end: 5 mrad or 5 mm of motion is left to the box.) A slab's own joint does not
    // count: the slab tapers to zero width at the segment's other end, where the rule would cut the
    // path into ever shorter stretches, each proving the whole box of the other joints there again
    // (the hull stays a sound bound whatever the stretch's length; a stretch that fails is still
    // split below).
    Eigen::VectorXd counted = motion;
    if (grown_joint >= 0) counted[grown_joint] = 0;
    const bool dominated = (counted.array() > 0.5 * half.array() + 0.005).any();
    if (splittable && dominated) {
      const double tm = (t0 + t1) / 2;
      stack.push_back({tm, t1});
      stack.push_back({t0, tm});
      continue;
    }
    const long remaining =
        std::min(budget.max_leaves - (stats.leaves - start), budget.leaf_limit - stats.leaves);
    if (remaining <= 0) {
      if (failure) {
        failure->lower = lo;
        failure->upper = hi;
        failure->budget = true;
        failure->t0 = t0;
        failure->t1 = t1;
      }
      return false;
    }
    // Joint splits within a share of the remaining budget; when they do not suffice, a shorter
    // stretch of the path may (unless the budget says not to cut: then the whole remaining budget).
    const bool worth_splitting =
        budget.split_path_on_failure && (motion.array() > 0.05 * half.array() + 1e-4).any();
    const long share = splittable && worth_splitting ? std::max(64L, remaining / 16) : remaining;
    CertifyFailure local;
    if (region_free_impl(ctx, lo, hi, stats, &local, std::min(share, remaining), budget.leaf_limit, pairs)) {
      if (proven) proven->emplace_back(t0, t1);
      continue;
    }
    // Not proven: is there a colliding configuration in the region itself (the boxes at t0, t1)?
    const Eigen::VectorXd q0 = (lo0 + hi0) / 2, q1 = (lo1 + hi1) / 2;
    for (int end = 0; end < 2 && !local.centre_hits; ++end) {
      CertifyFailure hit;
      if (!probe(ctx, end ? lo1 : lo0, end ? hi1 : hi0, end ? q1 : q0, budget.leaf_limit, stats, &hit)) {
        local = hit;
        local.t0 = local.t1 = end ? t1 : t0;
        if (failure) *failure = local;
        return false;
      }
    }
    if (splittable && worth_splitting && local.split_joint >= 0 && !local.centre_hits) {
      const double tm = (t0 + t1) / 2;
      stack.push_back({tm, t1});
      stack.push_back({t0, tm});
      continue;
    }
    local.t0 = t0;
    local.t1 = t1;
    if (failure) *failure = local;
    return false;
  }
  return true;
}

}  // namespace leeway
