#include "leeway/core/certify.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <tuple>

#include "leeway/core/error.hpp"

namespace leeway {
namespace {

// A joint box being tested: its bounds, depth, and the (link, obstacle) pairs its parent could not
// separate (pairs separated over a box stay separated over every sub-box).
struct Cell {
  Eigen::VectorXd lower, upper;
  int depth = 0;
  std::vector<int> pairs;
  int split = -1;  // the joint to split next (set when the cell waits in the heap)
};

Eigen::Vector3d vec3(const double* p) { return Eigen::Vector3d(p[0], p[1], p[2]); }

// True when `box` grown by `grow` [m] on every side touches or overlaps the obstacle: a box by the
// separating-axis test, a plane as the half-space below its surface (normal = its z axis).
bool touches(const Box& box, double grow, const Box& obstacle, bool plane) {
  Box grown = box;
  grown.half_size.array() += grow;
  if (!plane) return box_penetration(grown, obstacle) >= 0;
  const Eigen::Vector3d nrm = obstacle.rotation.col(2);
  return nrm.dot(box.center - obstacle.center) -
             (box.rotation.transpose() * nrm).cwiseAbs().dot(grown.half_size) <=
         0;
}

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

}  // namespace

void CertifyStats::add(const CertifyStats& o) {
  leaves += o.leaves;
  max_depth = std::max(max_depth, o.max_depth);
  pair_tests += o.pair_tests;
}

Certifier::Certifier(const Scene& scene, CertifyOptions options)
    : scene_(&scene), options_(options), state_(scene) {
  const mjModel& m = scene.model();
  std::vector<int> robot_index(static_cast<size_t>(m.njnt), -1);
  for (int i = 0; i < scene.dof(); ++i)
    robot_index[static_cast<size_t>(scene.joints()[static_cast<size_t>(i)].id)] = i;
  for (const auto& j : scene.joints()) prismatic_.push_back(j.prismatic);

  for (int g : scene.link_geoms()) {
    Link link;
    link.geom = g;
    // The bodies from the geom's body up to the world, then reversed: base to tip.
    std::vector<int> bodies;
    for (int b = m.geom_bodyid[g]; b > 0; b = m.body_parentid[b]) bodies.push_back(b);
    std::reverse(bodies.begin(), bodies.end());
    // Joints in kinematic order (within a body, in model order, as mj_kinematics applies them).
    std::vector<int> jids;
    std::vector<size_t> body_of_joint;  // index into `bodies`
    for (size_t k = 0; k < bodies.size(); ++k)
      for (int jj = 0; jj < m.body_jntnum[bodies[k]]; ++jj) {
        jids.push_back(m.body_jntadr[bodies[k]] + jj);
        body_of_joint.push_back(k);
      }
    const double half_norm = [&] {
      const Box b0 = geom_box(m, state_.data(), g);
      return std::isfinite(b0.half_size.norm()) ? b0.half_size.norm() : 0.0;
    }();
    for (size_t p = 0; p < jids.size(); ++p) {
      const int jid = jids[p];
      const int r = robot_index[static_cast<size_t>(jid)];
      LEEWAY_DEMAND(r >= 0);  // the scene recognises every joint on a link's chain as a robot joint
      link.joints.push_back(r);
      // Bound of |x - o_j| over every configuration, by the triangle inequality over the offsets of
      // the chain: the anchor's offset in its body, every later body's position in its parent, the
      // shift of a body's origin by its own joints (a later hinge: at most twice its anchor offset;
      // a later slide: its longest travel from the reference position within its limits) and the
      // geom's position in its body. Rotations keep lengths.
      double lever = vec3(m.jnt_pos + 3 * jid).norm();
      for (size_t q = p + 1; q < jids.size(); ++q) {
        const int later = jids[q];
        lever += 2 * vec3(m.jnt_pos + 3 * later).norm();
        if (m.jnt_type[later] == mjJNT_SLIDE) {
          const double ref = m.qpos0[m.jnt_qposadr[later]];
          const auto& joint = scene.joints()[static_cast<size_t>(robot_index[static_cast<size_t>(later)])];
          lever += std::max(std::abs(joint.lower - ref), std::abs(joint.upper - ref));
        }
      }
      for (size_t k = body_of_joint[p] + 1; k < bodies.size(); ++k)
        lever += vec3(m.body_pos + 3 * bodies[k]).norm();
      lever += vec3(m.geom_pos + 3 * g).norm();
      link.lever.push_back(lever);
    }
    link.corner_lever = half_norm;
    links_.push_back(std::move(link));
  }
  // Obstacles are static: their world boxes once.
  state_.set(scene.lower_limits().cwiseMax(0).cwiseMin(scene.upper_limits()));
  for (int g : scene.obstacle_geoms()) {
    Obstacle o;
    o.geom = g;
    o.box = geom_box(m, state_.data(), g);
    o.plane = m.geom_type[g] == mjGEOM_PLANE;
    o.radius = o.plane ? INFINITY : o.box.half_size.norm();
    obstacles_.push_back(o);
  }
  // Self pairs: the geom on the later part moves against the other (docs/algorithm.md,
  // "Self-collision"). `shared` counts the link's joints at or above the two geoms' deepest common
  // body: they move both geoms rigidly, so they do not change the pair's distance.
  std::vector<int> link_of(static_cast<size_t>(m.ngeom), -1);
  for (size_t i = 0; i < links_.size(); ++i)
    link_of[static_cast<size_t>(links_[i].geom)] = static_cast<int>(i);
  auto chain = [&](int body) {
    std::vector<int> out;
    for (int b = body; b > 0; b = m.body_parentid[b]) out.push_back(b);
    return out;
  };
  auto shared_joints = [&](const Link& link, const std::vector<int>& common) {
    int n = 0;
    for (int r : link.joints) {
      const int body = m.jnt_bodyid[scene.joints()[static_cast<size_t>(r)].id];
      if (std::find(common.begin(), common.end(), body) != common.end()) ++n;
    }
    return n;
  };
  for (const RobotPair& rp : scene.self_pairs()) {
    const std::vector<int> c1 = chain(m.geom_bodyid[rp.geom1]), c2 = chain(m.geom_bodyid[rp.geom2]);
    std::vector<int> common;  // the deepest common body and its ancestors
    for (int b : c2)
      if (std::find(c1.begin(), c1.end(), b) != c1.end()) common.push_back(b);
    SelfPair sp;
    sp.link = link_of[static_cast<size_t>(rp.geom2)];
    LEEWAY_DEMAND(sp.link >= 0);  // the later part moves with a joint: its geom is a link
    sp.shared = shared_joints(links_[static_cast<size_t>(sp.link)], common);
    sp.other_geom = rp.geom1;
    sp.other_link = link_of[static_cast<size_t>(rp.geom1)];
    if (sp.other_link >= 0) {
      const Link& ol = links_[static_cast<size_t>(sp.other_link)];
      sp.other_shared = shared_joints(ol, common);
      if (sp.other_shared == static_cast<int>(ol.joints.size())) sp.other_link = -1;  // on the chain: still
    }
    self_pairs_.push_back(sp);
  }
  // Grouped by link and shared joints, so that a leaf builds each link's bound once per group.
  std::stable_sort(self_pairs_.begin(), self_pairs_.end(), [](const SelfPair& a, const SelfPair& b) {
    return std::tie(a.link, a.shared) < std::tie(b.link, b.shared);
  });
  obstacle_pairs_ = static_cast<int>(links_.size() * obstacles_.size());
  all_pairs_.resize(static_cast<size_t>(obstacle_pairs_) + self_pairs_.size());
  for (size_t i = 0; i < all_pairs_.size(); ++i) all_pairs_[i] = static_cast<int>(i);
  // The joints each pair depends on: a link's chain against an obstacle; for a self pair, the
  // joints below the two geoms' deepest common body.
  pairs_moved_by_.assign(static_cast<size_t>(scene.dof()), {});
  for (int pair : all_pairs_) {
    std::vector<bool> moves(static_cast<size_t>(scene.dof()), false);
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
    for (int r = 0; r < scene.dof(); ++r)
      if (moves[static_cast<size_t>(r)]) pairs_moved_by_[static_cast<size_t>(r)].push_back(pair);
  }
}

bool Certifier::leaf_free(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, CertifyStats& stats,
                          CertifyFailure* failure) {
  check_box(*scene_, lower, upper);
  std::vector<int> pairs = all_pairs_;
  return leaf_free_impl(lower, upper, pairs, stats, failure);
}

// One leaf: every pair in `pairs` is tested at the box's centre c with half-widths h; on return
// `pairs` holds the pairs that could not be separated (empty: the box is free). Every pair is
// tested, not only up to the first failing one: the worst-first order below needs the worst.
bool Certifier::leaf_free_impl(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                               std::vector<int>& pairs, CertifyStats& stats, CertifyFailure* failure,
                               const Eigen::VectorXd* blame) {
  ++stats.leaves;
  // Scratch kept across calls (capacity only): a leaf allocates nothing once the first has run.
  // One Certifier per thread and no recursion, so thread-local storage is enough.
  thread_local Eigen::VectorXd c, h, hl;
  c = (lower + upper) / 2;
  h = (upper - lower) / 2;
  state_.set(c);
  const mjModel& m = scene_->model();
  const mjData& d = state_.data();
  const double margin = options_.margin;
  const size_t nobs = obstacles_.size();
  thread_local std::vector<int> failing;
  failing.clear();
  int last_link = -1, last_shared = 0;
  if (failure) {
    failure->centre_hits = false;
    failure->gap = 0.0;
  }

  // Per link (computed when its first pair comes up): world box at c and an isotropic bound; when a
  // pair needs more (built once per link and leaf): joint Jacobian columns at the box centre,
  // derivatives of the box axes, and the remainders.
  Box box;
  thread_local std::vector<Eigen::Vector3d> jac;       // d x / d q_i at c
  thread_local std::vector<Eigen::Matrix3d> axis_jac;  // column k: d e_k / d q_i at c
  thread_local std::vector<Eigen::Vector3d> axis;      // joint axes at c
  thread_local std::vector<double> theta_before;  // rotation the hinges before each joint can give its axis
  // One second-order term (p, q) of the remainder, see below.
  struct Term {
    size_t p = 0;
    double coef = 0, iso = 0, var = 0, var_e = 0;
    bool slide = false;
    Eigen::Vector3d w = Eigen::Vector3d::Zero();
    Eigen::Matrix3d we = Eigen::Matrix3d::Zero();
  };
  thread_local std::vector<Term> terms;
  bool terms_ready = false;
  thread_local std::vector<double> r_pos,
      r_rot;                            // per joint p: the remainder terms (p, q >= p) with |n x a_p| = 1
  thread_local std::vector<double> dv;  // per joint q: |v_q(q) - v_q(c)|, see below
  // r_pos, r_rot and the isotropic terms of the link `full_link` with no joint held.
  thread_local std::vector<double> full_r_pos, full_r_rot, iso_term;
  int full_link = -1;
  size_t link_n = 0;                     // the current link's joint count, ...
  double link_theta = 0;                 // ... the rotation all its hinges can give, ...
  int link_index = 0;                    // ... and its index in links_
  double iso = 0;                        // radius of a sphere around x(c) holding the swept link
  double iso_cheap = 0;                  // a larger one, without the Jacobian
  double rem_iso = 0;                    // the remainder's isotropic size
  bool link_ready = false;               // the current link's bound is built
  thread_local Eigen::Matrix3Xd motion;  // see below
  Eigen::Index motion_cols = 0;
  double lever_radius = 0;  // the loose reference's inflation

  auto build_terms = [&] {
    const size_t n = link_n;
    const double theta = link_theta;
    const int li = link_index;
    const Link& l = links_[static_cast<size_t>(li)];
    terms.clear();
    for (size_t p = 0; p < n; ++p) {
      const int rp = l.joints[p];
      if (prismatic_[static_cast<size_t>(rp)]) continue;
      for (size_t q = p; q < n; ++q) {
        const int rq = l.joints[q];
        Term t;
        t.p = p;
        t.coef = (p == q ? 0.5 : 1.0) * hl[rp] * hl[rq];
        if (t.coef == 0) continue;
        const bool slide = prismatic_[static_cast<size_t>(rq)];
        const Eigen::Vector3d anchor = vec3(d.xanchor + 3 * scene_->joints()[static_cast<size_t>(rq)].id);
        t.w = slide ? Eigen::Vector3d(axis[p].cross(axis[q]))
                    : Eigen::Vector3d(axis[p].cross(axis[q].cross(box.center - anchor)));
        t.iso = slide ? 1.0 : l.lever[q];
        t.var = t.iso * (theta_before[p] + theta_before[q]) + (slide ? 0.0 : dv[q]);
        t.slide = slide;
        if (!slide) {
          for (int k = 0; k < 3; ++k) t.we.col(k) = axis[p].cross(axis[q].cross(box.rotation.col(k)));
          t.var_e = theta_before[p] + theta_before[q] + theta;
        }
        terms.push_back(t);
      }
    }
    terms_ready = true;
  };

  Obstacle other;  // a self pair's other robot geom, at c (grown by its own motion)
  Box other_at_c;  // ... and as it is at c, for the centre test
  for (int pair : pairs) {
    ++stats.pair_tests;
    // An obstacle pair (link, obstacle), or a self pair: the link against another robot geom. The
    // distance between two robot geoms does not depend on the joints above their common ancestor
    // (they move both rigidly), so those joints are held at c: the link's bound uses half-widths
    // hl with them zeroed, and the other geom stands at its pose at c, grown by what the joints
    // below the common ancestor can move it (a sound isotropic bound; zero on one chain, where
    // the other geom is the ancestor's). docs/algorithm.md ("Self-collision") has the argument.
    const bool self = pair >= obstacle_pairs_;
    const SelfPair* pair_info = self ? &self_pairs_[static_cast<size_t>(pair - obstacle_pairs_)] : nullptr;
    const int li = self ? pair_info->link : pair / static_cast<int>(nobs);
    const int shared = self ? pair_info->shared : 0;
    const Link& link = links_[static_cast<size_t>(li)];
    if (self) {
      other.geom = pair_info->other_geom;
      other.box = other_at_c = geom_box(m, d, pair_info->other_geom);
      double grow = 0;
      if (pair_info->other_link >= 0) {
        const Link& ol = links_[static_cast<size_t>(pair_info->other_link)];
        for (size_t p = static_cast<size_t>(pair_info->other_shared); p < ol.joints.size(); ++p) {
          const int r = ol.joints[p];
          grow += h[r] * (prismatic_[static_cast<size_t>(r)] ? 1.0 : ol.lever[p] + ol.corner_lever);
        }
      }
      other.box.half_size.array() += grow;
      other.radius = other.box.half_size.norm();
    }
    const Obstacle& obs = self ? other : obstacles_[static_cast<size_t>(pair) % nobs];
    if (li != last_link || shared != last_shared) {
      last_link = li;
      last_shared = shared;
      hl = h;
      for (int p = 0; p < shared; ++p) hl[link.joints[static_cast<size_t>(p)]] = 0;
      box = geom_box(m, d, link.geom);
      link_ready = false;
      // The remainder's isotropic size, and a sphere around x(c) that holds the swept link without
      // the Jacobian (|d x / d q_p| <= lever_p, 1 for a slide): most pairs are separated by it, and
      // the link's full bound below is built only for the pairs it does not separate.
      const size_t n = link.joints.size();
      // Term p of these sums involves only joints p and later, so with the first `shared` joints
      // held (their terms zero) the others are the same as for the whole link: they are built
      // once per link and leaf, not once per self pair group (a link on a long chain has as many
      // groups as joints, which made a leaf's cost grow with the fourth power of the joint count).
      const size_t first = static_cast<size_t>(shared);
      if (li != full_link) {
        full_link = li;
        full_r_pos.assign(n, 0.0);
        full_r_rot.assign(n, 0.0);
        iso_term.assign(n, 0.0);
        for (size_t p = 0; p < n; ++p) {
          const int rp = link.joints[p];
          const bool slide_p = prismatic_[static_cast<size_t>(rp)];
          iso_term[p] = h[rp] * (slide_p ? 1.0 : link.lever[p]);
          if (slide_p) continue;
          for (size_t q = p; q < n; ++q) {
            const int rq = link.joints[q];
            const bool slide = prismatic_[static_cast<size_t>(rq)];
            const double coef = (p == q ? 0.5 : 1.0) * h[rp] * h[rq];
            full_r_pos[p] += coef * (slide ? 1.0 : link.lever[q]);
            if (!slide) full_r_rot[p] += coef;
          }
        }
      }
      rem_iso = 0;
      r_pos.assign(n, 0.0);
      r_rot.assign(n, 0.0);
      iso_cheap = box.half_size.norm();
      for (size_t p = first; p < n; ++p) {
        iso_cheap += iso_term[p];
        if (prismatic_[static_cast<size_t>(link.joints[p])]) continue;
        r_pos[p] = full_r_pos[p];
        r_rot[p] = full_r_rot[p];
        rem_iso += r_pos[p];
      }
      iso_cheap += rem_iso;
    }
    if (options_.bound == CertifyBound::kTaylor && !obs.plane &&
        (obs.box.center - box.center).norm() - iso_cheap - obs.radius > margin)
      continue;
    if (!link_ready) {
      link_ready = true;
      const size_t n = link.joints.size();
      jac.assign(n, Eigen::Vector3d::Zero());
      axis_jac.assign(n, Eigen::Matrix3d::Zero());
      lever_radius = 0;
      for (size_t p = 0; p < n; ++p) {
        const int r = link.joints[p];
        const int jid = scene_->joints()[static_cast<size_t>(r)].id;
        const Eigen::Vector3d a = vec3(d.xaxis + 3 * jid);
        if (prismatic_[static_cast<size_t>(r)]) {
          jac[p] = a;
          lever_radius += hl[r];
        } else {
          jac[p] = a.cross(box.center - vec3(d.xanchor + 3 * jid));
          for (int k = 0; k < 3; ++k) axis_jac[p].col(k) = a.cross(box.rotation.col(k));
          lever_radius += hl[r] * (link.lever[p] + link.corner_lever);
        }
      }
      // Lagrange remainder along the segment from c to q: 1/2 sum_pq h_p h_q sup |n . d2x/dq_p dq_q|.
      // For p proximal to (or equal to) q, d2x/dq_p dq_q = a_p x (a_q x v_q), v_q = x - o_q (hinge
      // q, |v_q| <= lever_q), or a_p x a_q (slide q), and 0 when p is a slide. Two bounds of its
      // projection on n over the box, the smaller one is used:
      //  - |n x a_p| |a_q x v_q| <= s_p(n) lever_q, s_p(n) = min(1, |n x a_p(c)| + theta_<p);
      //  - its value at c plus how far it can move: |n . w_pq(c)| + lever_q (theta_<p + theta_<q)
      //    + |v_q(q) - v_q(c)|, the last at most theta_<=q lever_q + sum_{r>q} h_r lever_r.
      // theta_<p is the rotation the hinges before p can give a_p. Box axes e likewise, with
      // a_q x e (|.| <= 1) and |e(q) - e(c)| <= theta (every hinge).
      axis.assign(n, Eigen::Vector3d::Zero());
      theta_before.assign(n, 0.0);
      double before = 0;
      for (size_t p = 0; p < n; ++p) {
        const int rp = link.joints[p];
        axis[p] = vec3(d.xaxis + 3 * scene_->joints()[static_cast<size_t>(rp)].id);
        theta_before[p] = before;
        if (!prismatic_[static_cast<size_t>(rp)]) before += hl[rp];
      }
      const double theta = before;
      // |v_q(q) - v_q(c)| per q.
      dv.assign(n, 0.0);
      for (size_t q = 0; q < n; ++q) {
        const int rq = link.joints[q];
        if (prismatic_[static_cast<size_t>(rq)]) continue;
        dv[q] = (theta_before[q] + hl[rq]) * link.lever[q];
        for (size_t r = q + 1; r < n; ++r) {
          const int rr = link.joints[r];
          dv[q] += hl[rr] * (prismatic_[static_cast<size_t>(rr)] ? 1.0 : link.lever[r]);
        }
      }
      // The remainder's terms are built only for pairs that the sphere test does not separate.
      terms_ready = false;
      link_n = n;
      link_theta = theta;
      link_index = li;
      iso = rem_iso + box.half_size.norm();
      for (size_t p = 0; p < n; ++p) iso += hl[link.joints[p]] * jac[p].norm();
      // The first-order motion's directions, scaled by the half-widths: first(n, h) below is the
      // sum of |n . column|.
      // (It only grows: resizing to another size would allocate.)
      if (motion.cols() < static_cast<Eigen::Index>(4 * n))
        motion.resize(3, static_cast<Eigen::Index>(4 * n));
      Eigen::Index col = 0;
      for (size_t p = 0; p < n; ++p) {
        const double hp = hl[link.joints[p]];
        if (hp == 0) continue;
        motion.col(col++) = hp * jac[p];
        if (prismatic_[static_cast<size_t>(link.joints[p])]) continue;
        for (int k = 0; k < 3; ++k) motion.col(col++) = (hp * box.half_size[k]) * axis_jac[p].col(k);
      }
      motion_cols = col;
    }

    bool separated = false;
    // The axis on which the pair came closest to separating, for the blame below.
    Eigen::Vector3d best_axis = (obs.box.center - box.center).normalized();
    double best_gap = -std::numeric_limits<double>::infinity();
    // The swept link's projected radius on a unit axis n is first(n, h) + extent(n) + a remainder;
    // first() and extent() are the first-order motion and the box at c, and the remainder is
    // bounded cheaply (s_p(n) times every term's isotropic bound) or refined (per term, the
    // smaller of that and its value at c plus its variation), see above. first(n, h) is evaluated
    // as the sum of |n . column| of `motion` (the same terms, scaled once per link); first() with
    // other weights w per joint serves the blame below (a probe's offsets, where h is zero).
    auto first = [&](const Eigen::Vector3d& nrm, const Eigen::VectorXd& w) {
      double r = 0;
      for (size_t p = 0; p < jac.size(); ++p) {
        const double wp = w[link.joints[p]];
        if (wp == 0) continue;
        r += wp * std::abs(nrm.dot(jac[p]));
        for (int k = 0; k < 3; ++k) r += box.half_size[k] * wp * std::abs(nrm.dot(axis_jac[p].col(k)));
      }
      return r;
    };
    auto extent = [&](const Eigen::Vector3d& nrm) {
      return (box.rotation.transpose() * nrm).cwiseAbs().dot(box.half_size);
    };
    auto s_of = [&](const Eigen::Vector3d& nrm, size_t p) {
      return std::min(1.0, nrm.cross(axis[p]).norm() + theta_before[p]);
    };
    const double half_sum = box.half_size.sum();
    auto rem_cheap = [&](const Eigen::Vector3d& nrm) {
      double r = 0;
      for (size_t p = 0; p < axis.size(); ++p)
        if (r_pos[p] > 0) r += s_of(nrm, p) * (r_pos[p] + half_sum * r_rot[p]);
      return r;
    };
    auto rem_refined = [&](const Eigen::Vector3d& nrm) {
      if (!terms_ready) build_terms();
      double s_p[16];
      const size_t np = std::min<size_t>(axis.size(), 16);
      for (size_t p = 0; p < np; ++p) s_p[p] = s_of(nrm, p);
      double rem_pos = 0;
      Eigen::Vector3d rem_rot = Eigen::Vector3d::Zero();
      for (const Term& t : terms) {
        const double sp = t.p < np ? s_p[t.p] : 1.0;
        rem_pos += t.coef * std::min(sp * t.iso, std::abs(nrm.dot(t.w)) + t.var);
        if (!t.slide)
          for (int k = 0; k < 3; ++k)
            rem_rot[k] += t.coef * std::min(sp, std::abs(nrm.dot(t.we.col(k))) + t.var_e);
      }
      return rem_pos + box.half_size.dot(rem_rot);
    };
    // Whether the pair is separated on axis n given the signed distance `apart` between the
    // link's centre and the obstacle's near face along n, with the obstacle's extent removed.
    auto separated_on = [&](const Eigen::Vector3d& nrm, double apart) {
      const double base =
          apart - (motion.leftCols(motion_cols).transpose() * nrm).cwiseAbs().sum() - extent(nrm);
      // The refined remainder only where the cheap one fails and the rest leaves room; the gap of
      // an axis (for the blame and the search order) is its best bound either way.
      double g = base - rem_cheap(nrm);
      bool sep = g > margin;
      if (!sep && base > margin) {
        g = base - rem_refined(nrm);
        sep = g > margin;
      }
      if (g > best_gap) {
        best_gap = g;
        best_axis = nrm;
      }
      return sep;
    };
    if (options_.bound == CertifyBound::kLever) {
      // The link's box at c grown by lever_radius on every side, against the obstacle.
      separated = !touches(box, lever_radius + margin, obs.box, obs.plane);
    } else {
      const Eigen::Vector3d diff = obs.box.center - box.center;
      if (!obs.plane && diff.norm() - iso - obs.radius > margin) {
        separated = true;
      } else if (obs.plane) {
        const Eigen::Vector3d nrm = obs.box.rotation.col(2);
        separated = separated_on(nrm, nrm.dot(box.center - obs.box.center));
      } else {
        auto try_axis = [&](const Eigen::Vector3d& candidate) {
          const double len = candidate.norm();
          if (len < 1e-9) return false;
          const Eigen::Vector3d nrm = candidate / len;
          const double ro = (obs.box.rotation.transpose() * nrm).cwiseAbs().dot(obs.box.half_size);
          return separated_on(nrm, std::abs(nrm.dot(diff)) - ro);
        };
        for (int k = 0; k < 3 && !separated; ++k) separated = try_axis(obs.box.rotation.col(k));
        for (int k = 0; k < 3 && !separated; ++k) separated = try_axis(box.rotation.col(k));
        for (int k = 0; k < 3 && !separated; ++k)
          for (int l = 0; l < 3 && !separated; ++l)
            separated = try_axis(box.rotation.col(k).cross(obs.box.rotation.col(l)));
        if (!separated) separated = try_axis(diff);
      }
    }
    if (separated) continue;
    if (failure) failure->gap = std::min(failure->gap, std::isfinite(best_gap) ? best_gap - margin : -1e9);
    if (failing.empty() && failure) {
      // Blame: the joint whose motion moves this link most along the axis that came closest to
      // separating the pair (first order, plus its share of the remainder); it is the one to split
      // or shrink. Weights: the half-widths, or `blame` when given (a probe's offsets).
      thread_local Eigen::VectorXd w;
      w = blame ? *blame : hl;
      for (int p = 0; p < shared; ++p) w[link.joints[static_cast<size_t>(p)]] = 0;
      int best = -1;
      double best_contribution = 0;
      for (size_t p = 0; p < link.joints.size(); ++p) {
        const int r = link.joints[p];
        Eigen::VectorXd only = Eigen::VectorXd::Zero(w.size());
        only[r] = w[r];
        double contribution = first(best_axis, only);
        if (!prismatic_[static_cast<size_t>(r)]) contribution += 0.5 * w[r] * w[r] * link.lever[p];
        if (options_.bound == CertifyBound::kLever)
          contribution =
              w[r] * (prismatic_[static_cast<size_t>(r)] ? 1.0 : link.lever[p] + link.corner_lever);
        if (contribution > best_contribution) {
          best_contribution = contribution;
          best = r;
        }
      }
      failure->lower = lower;
      failure->upper = upper;
      failure->link_geom = link.geom;
      failure->obstacle_geom = obs.geom;
      failure->self = self;
      failure->split_joint = best;
      failure->budget = false;
    }
    // Does the centre configuration itself come within the margin? Then no split can help.
    if (failure && !failure->centre_hits)
      failure->centre_hits = touches(box, margin, self ? other_at_c : obs.box, obs.plane);
    failing.push_back(pair);
  }
  pairs.swap(failing);
  return pairs.empty();
}

bool Certifier::region_free_impl(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                                 CertifyStats& stats, CertifyFailure* failure, long budget,
                                 const std::vector<int>& pairs) {
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
    if (leaf_free_impl(cell.lower, cell.upper, cell.pairs, stats, &local)) return true;
    const bool exhausted = stats.leaves - start >= budget || stats.leaves >= options_.leaf_limit ||
                           cell.depth >= options_.max_depth;
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
  if (stats.leaves >= options_.leaf_limit) return out_of_leaves(lower, upper, failure);
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

bool Certifier::probe(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                      const Eigen::VectorXd& nominal, CertifyStats& stats, CertifyFailure* failure) {
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
    if (stats.leaves >= options_.leaf_limit) return out_of_leaves(lower, upper, failure);
    std::vector<int> pairs = all_pairs_;
    const Eigen::VectorXd offsets = (p - nominal).cwiseAbs();
    if (leaf_free_impl(p, p, pairs, stats, &local, &offsets)) continue;
    local.centre_hits = true;
    if (failure) *failure = local;
    return false;
  }
  return true;
}

bool Certifier::segment_probe(const Eigen::VectorXd& lower_a, const Eigen::VectorXd& upper_a,
                              const Eigen::VectorXd& lower_b, const Eigen::VectorXd& upper_b,
                              const Eigen::VectorXd& qa, const Eigen::VectorXd& qb, int samples,
                              CertifyStats& stats, CertifyFailure* failure) {
  check_box(*scene_, qa, qa);
  check_box(*scene_, qb, qb);
  check_box(*scene_, lower_a, upper_a);
  check_box(*scene_, lower_b, upper_b);
  CertifyFailure local;
  for (double t : {0.0, 1.0, 0.5, 0.25, 0.75}) {
    if (probe((1 - t) * lower_a + t * lower_b, (1 - t) * upper_a + t * upper_b, (1 - t) * qa + t * qb, stats,
              &local))
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
    if (probe(p, p, nominal, stats, &local)) continue;
    local.t0 = local.t1 = t;
    if (failure) *failure = local;
    return false;
  }
  return true;
}

bool Certifier::region_free(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, CertifyStats& stats,
                            CertifyFailure* failure) {
  check_box(*scene_, lower, upper);
  if (!probe(lower, upper, (lower + upper) / 2, stats, failure)) return false;
  return region_free_impl(lower, upper, stats, failure, options_.max_leaves, all_pairs_);
}

bool Certifier::segment_free(const Eigen::VectorXd& lower_a, const Eigen::VectorXd& upper_a,
                             const Eigen::VectorXd& lower_b, const Eigen::VectorXd& upper_b,
                             CertifyStats& stats, CertifyFailure* failure,
                             std::vector<std::pair<double, double>>* proven, int grown_joint) {
  check_box(*scene_, lower_a, upper_a);
  check_box(*scene_, lower_b, upper_b);
  if (grown_joint >= scene_->dof()) throw InputError("certify: no joint " + std::to_string(grown_joint));
  const std::vector<int>& pairs =
      grown_joint < 0 ? all_pairs_ : pairs_moved_by_[static_cast<size_t>(grown_joint)];
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
    // split without end: 5 mrad or 5 mm of motion is left to the box.)
    const bool dominated = (motion.array() > 0.5 * half.array() + 0.005).any();
    if (splittable && dominated) {
      const double tm = (t0 + t1) / 2;
      stack.push_back({tm, t1});
      stack.push_back({t0, tm});
      continue;
    }
    const long remaining =
        std::min(options_.max_leaves - (stats.leaves - start), options_.leaf_limit - stats.leaves);
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
    // stretch of the path may.
    const bool worth_splitting = (motion.array() > 0.05 * half.array() + 1e-4).any();
    const long share = splittable && worth_splitting ? std::max(64L, remaining / 16) : remaining;
    CertifyFailure local;
    if (region_free_impl(lo, hi, stats, &local, std::min(share, remaining), pairs)) {
      if (proven) proven->emplace_back(t0, t1);
      continue;
    }
    // Not proven: is there a colliding configuration in the region itself (the boxes at t0, t1)?
    const Eigen::VectorXd q0 = (lo0 + hi0) / 2, q1 = (lo1 + hi1) / 2;
    for (int end = 0; end < 2 && !local.centre_hits; ++end) {
      CertifyFailure hit;
      if (!probe(end ? lo1 : lo0, end ? hi1 : hi0, end ? q1 : q0, stats, &hit)) {
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
