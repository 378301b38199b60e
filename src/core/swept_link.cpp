#include "leeway/core/swept_link.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace leeway {

SweepObstacle sweep_obstacle(int geom, const Shape& shape) {
  SweepObstacle o;
  o.geom = geom;
  o.shape = shape;
  o.box = shape.box;
  o.plane = shape.plane();
  o.radius = o.plane ? INFINITY : shape.radius;
  return o;
}

bool touches(const Box& box, double grow, const Box& obstacle, bool plane) {
  Box grown = box;
  grown.half_size.array() += grow;
  if (!plane) return box_penetration(grown, obstacle) >= 0;
  const Eigen::Vector3d nrm = obstacle.rotation.col(2);
  return nrm.dot(box.center - obstacle.center) -
             (box.rotation.transpose() * nrm).cwiseAbs().dot(grown.half_size) <=
         0;
}

void SweptLink::start(const LinkChain& link, int link_id, const Eigen::VectorXd& h, int held,
                      const mjModel& m, const mjData& d) {
  link_ = &link;
  d_ = &d;
  held_ = held;
  const size_t n = link.joints.size();
  // A pivot box holds what its frozen entries sweep: they are held at the centre.
  const Eigen::VectorXd* hv = &h;
  if (link.body >= 0) {
    tail_held_ = h;
    for (size_t p = link.frozen_from; p < n; ++p) tail_held_[link.joints[p]] = 0;
    hv = &tail_held_;
    const Eigen::Vector3d origin = vec3(d.xpos + 3 * link.body);
    const Eigen::Matrix3d frame = mat3(d.xmat + 9 * link.body);
    box_.center = origin + frame * link.local_pos;
    box_.rotation =
        link.translate_only ? Eigen::Matrix3d::Identity() : Eigen::Matrix3d(frame * link.local_rot);
    box_.half_size = link.half_size;
    shape_ = box_shape(box_);
  } else {
    shape_ = geom_shape(m, d, link.geom, link.mesh ? &link.hull : nullptr);
    box_ = shape_.box;
  }
  hl_ = *hv;
  for (int p = 0; p < held; ++p) hl_[link.joints[static_cast<size_t>(p)]] = 0;
  built_ = false;
  // The remainder's isotropic size, and a sphere around x(c) that holds the swept link without
  // the Jacobian (|d x / d q_p| <= lever_p, 1 for a slide): most pairs are separated by it, and
  // the full bound (build()) is built only for the pairs it does not separate.
  // Term p of these sums involves only joints p and later, so with the first `held` joints held
  // (their terms zero) the others are the same as for the whole link: they are built once per
  // link and leaf, not once per self pair group (a link on a long chain has as many groups as
  // joints, which made a leaf's cost grow with the fourth power of the joint count).
  const size_t first = static_cast<size_t>(held);
  if (link_id != cached_link_) {
    cached_link_ = link_id;
    full_r_pos_.assign(n, 0.0);
    full_r_rot_.assign(n, 0.0);
    iso_term_.assign(n, 0.0);
    for (size_t p = 0; p < n; ++p) {
      const int rp = link.joints[p];
      const bool slide_p = link.slide[p];
      iso_term_[p] = (*hv)[rp] * (slide_p ? 1.0 : link.lever[p]);
      if (slide_p) continue;
      for (size_t q = p; q < n; ++q) {
        const int rq = link.joints[q];
        const bool slide = link.slide[q];
        const double coef = (p == q ? 0.5 : 1.0) * (*hv)[rp] * (*hv)[rq];
        full_r_pos_[p] += coef * (slide ? 1.0 : link.lever[q]);
        if (!slide) full_r_rot_[p] += coef;
      }
    }
  }
  rem_iso_ = 0;
  r_pos_.assign(n, 0.0);
  r_rot_.assign(n, 0.0);
  iso_cheap_ = box_.half_size.norm();
  for (size_t p = first; p < n; ++p) {
    iso_cheap_ += iso_term_[p];
    if (link.slide[p]) continue;
    r_pos_[p] = full_r_pos_[p];
    r_rot_[p] = link.translate_only ? 0.0 : full_r_rot_[p];
    rem_iso_ += r_pos_[p];
  }
  iso_cheap_ += rem_iso_;
}

void SweptLink::build() {
  if (built_) return;
  built_ = true;
  const LinkChain& link = *link_;
  const mjData& d = *d_;
  const size_t n = link.joints.size();
  jac_.assign(n, Eigen::Vector3d::Zero());
  axis_jac_.assign(n, Eigen::Matrix3d::Zero());
  lever_radius_ = 0;
  for (size_t p = 0; p < n; ++p) {
    const int r = link.joints[p];
    const int jid = link.mj_joints[p];
    const Eigen::Vector3d a = vec3(d.xaxis + 3 * jid);
    if (link.slide[p]) {
      jac_[p] = a;
      lever_radius_ += hl_[r];
    } else {
      jac_[p] = a.cross(box_.center - vec3(d.xanchor + 3 * jid));
      if (!link.translate_only)
        for (int k = 0; k < 3; ++k) axis_jac_[p].col(k) = a.cross(box_.rotation.col(k));
      lever_radius_ += hl_[r] * (link.lever[p] + link.corner_lever);
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
  axis_.assign(n, Eigen::Vector3d::Zero());
  theta_before_.assign(n, 0.0);
  double before = 0;
  for (size_t p = 0; p < n; ++p) {
    axis_[p] = vec3(d.xaxis + 3 * link.mj_joints[p]);
    theta_before_[p] = before;
    if (!link.slide[p]) before += hl_[link.joints[p]];
  }
  theta_ = before;
  // |v_q(q) - v_q(c)| per q.
  dv_.assign(n, 0.0);
  for (size_t q = 0; q < n; ++q) {
    if (link.slide[q]) continue;
    dv_[q] = (theta_before_[q] + hl_[link.joints[q]]) * link.lever[q];
    for (size_t r = q + 1; r < n; ++r) dv_[q] += hl_[link.joints[r]] * (link.slide[r] ? 1.0 : link.lever[r]);
  }
  // The remainder's terms are built only for pairs that the cheap remainder does not separate.
  terms_built_ = false;
  iso_ = rem_iso_ + box_.half_size.norm();
  for (size_t p = 0; p < n; ++p) iso_ += hl_[link.joints[p]] * jac_[p].norm();
  // The first-order motion's directions, scaled by the half-widths: the first-order extent on n is
  // the sum of |n . column|. (The matrix only grows: resizing to another size would allocate.)
  if (motion_.cols() < static_cast<Eigen::Index>(4 * n)) motion_.resize(3, static_cast<Eigen::Index>(4 * n));
  Eigen::Index col = 0;
  for (size_t p = 0; p < n; ++p) {
    const double hp = hl_[link.joints[p]];
    if (hp == 0) continue;
    motion_.col(col++) = hp * jac_[p];
    if (link.slide[p] || link.translate_only) continue;
    for (int k = 0; k < 3; ++k) motion_.col(col++) = (hp * box_.half_size[k]) * axis_jac_[p].col(k);
  }
  motion_cols_ = col;
}

void SweptLink::build_terms() {
  const LinkChain& l = *link_;
  const size_t n = l.joints.size();
  terms_.clear();
  for (size_t p = 0; p < n; ++p) {
    const int rp = l.joints[p];
    if (l.slide[p]) continue;
    for (size_t q = p; q < n; ++q) {
      const int rq = l.joints[q];
      Term t;
      t.p = p;
      t.coef = (p == q ? 0.5 : 1.0) * hl_[rp] * hl_[rq];
      if (t.coef == 0) continue;
      const bool slide = l.slide[q];
      const Eigen::Vector3d anchor = vec3(d_->xanchor + 3 * l.mj_joints[q]);
      t.w = slide ? Eigen::Vector3d(axis_[p].cross(axis_[q]))
                  : Eigen::Vector3d(axis_[p].cross(axis_[q].cross(box_.center - anchor)));
      t.iso = slide ? 1.0 : l.lever[q];
      t.var = t.iso * (theta_before_[p] + theta_before_[q]) + (slide ? 0.0 : dv_[q]);
      t.turns_axes = !slide && !l.translate_only;
      if (t.turns_axes) {
        for (int k = 0; k < 3; ++k) t.we.col(k) = axis_[p].cross(axis_[q].cross(box_.rotation.col(k)));
        t.var_e = theta_before_[p] + theta_before_[q] + theta_;
      }
      terms_.push_back(t);
    }
  }
  terms_built_ = true;
}

double SweptLink::s_of(const Eigen::Vector3d& n, size_t p) const {
  return std::min(1.0, n.cross(axis_[p]).norm() + theta_before_[p]);
}

double SweptLink::motion_extent(const Eigen::Vector3d& n) const {
  return (motion_.leftCols(motion_cols_).transpose() * n).cwiseAbs().sum();
}

double SweptLink::box_extent(const Eigen::Vector3d& n) const {
  return (box_.rotation.transpose() * n).cwiseAbs().dot(box_.half_size);
}

double SweptLink::extent(const Eigen::Vector3d& n, int* hint) const {
  if (!shaped()) return box_extent(n);
  return shape_.support(n, hint) - n.dot(box_.center);
}

double SweptLink::remainder_cheap(const Eigen::Vector3d& n) const {
  const double half_sum = box_.half_size.sum();
  double r = 0;
  for (size_t p = 0; p < axis_.size(); ++p)
    if (r_pos_[p] > 0) r += s_of(n, p) * (r_pos_[p] + half_sum * r_rot_[p]);
  return r;
}

double SweptLink::remainder_refined(const Eigen::Vector3d& n) {
  if (!terms_built_) build_terms();
  double s_p[16];
  const size_t np = std::min<size_t>(axis_.size(), 16);
  for (size_t p = 0; p < np; ++p) s_p[p] = s_of(n, p);
  double rem_pos = 0;
  Eigen::Vector3d rem_rot = Eigen::Vector3d::Zero();
  for (const Term& t : terms_) {
    const double sp = t.p < np ? s_p[t.p] : 1.0;
    rem_pos += t.coef * std::min(sp * t.iso, std::abs(n.dot(t.w)) + t.var);
    if (t.turns_axes)
      for (int k = 0; k < 3; ++k) rem_rot[k] += t.coef * std::min(sp, std::abs(n.dot(t.we.col(k))) + t.var_e);
  }
  return rem_pos + box_.half_size.dot(rem_rot);
}

double SweptLink::contribution(const Eigen::Vector3d& n, size_t p, double w) const {
  if (w == 0) return 0.0;
  double r = 0;
  r += w * std::abs(n.dot(jac_[p]));
  for (int k = 0; k < 3; ++k) r += box_.half_size[k] * w * std::abs(n.dot(axis_jac_[p].col(k)));
  if (!link_->slide[p]) r += 0.5 * w * w * link_->lever[p];
  return r;
}

Separation separate(SweptLink& link, const SweepObstacle& obs, double margin) {
  Separation out;
  const Box& box = link.box();
  out.axis = (obs.box.center - box.center).normalized();
  double best_gap = -std::numeric_limits<double>::infinity();
  // Whether the pair is separated on axis n given the signed distance `apart` between the link's
  // centre and the obstacle's near face along n, with the obstacle's extent removed, and the link's
  // own extent toward it. The refined remainder only where the cheap one fails and the rest leaves
  // room; the gap of an axis (for the blame and the search order) is its best bound either way.
  auto separated_on = [&](const Eigen::Vector3d& nrm, double apart, double extent) {
    const double base = apart - link.motion_extent(nrm) - extent;
    double g = base - link.remainder_cheap(nrm);
    bool sep = g > margin;
    if (!sep && base > margin) {
      g = base - link.remainder_refined(nrm);
      sep = g > margin;
    }
    if (g > best_gap) {
      best_gap = g;
      out.axis = nrm;
    }
    return sep;
  };
  // Two boxes are tested on their 15 axes and the centre line. A round or mesh pair is tested the
  // same way on the boxes that hold the two shapes first (cheap, and where they are apart so are
  // the shapes), then on the shapes' supports, from the axis of their closest points on.
  const bool boxes = obs.shape.is_box() && !link.shaped();
  bool on_boxes = true;
  int hint_link[2] = {0, 0}, hint_obs[2] = {0, 0};  // mesh supports' climbing hints: toward, away
  const Eigen::Vector3d diff = obs.box.center - box.center;
  if (!obs.plane && diff.norm() - link.radius() - obs.radius > margin) {
    out.separated = true;
  } else if (obs.plane) {
    const Eigen::Vector3d nrm = obs.box.rotation.col(2);
    out.separated = separated_on(nrm, nrm.dot(box.center - obs.box.center), link.extent(-nrm));
  } else {
    // On unit axis n, the side (n or -n) where the two projections are further apart: the link's
    // extent toward the obstacle and the obstacle's support toward the link (exact for both).
    auto try_axis = [&](const Eigen::Vector3d& candidate) {
      const double len = candidate.norm();
      if (len < 1e-9) return false;
      const Eigen::Vector3d nrm = candidate / len;
      if (on_boxes) {
        const double ro = (obs.box.rotation.transpose() * nrm).cwiseAbs().dot(obs.box.half_size);
        return separated_on(nrm, std::abs(nrm.dot(diff)) - ro, link.box_extent(nrm));
      }
      const double p = nrm.dot(box.center);
      const double ahead = -obs.shape.support(-nrm, &hint_obs[0]) - p,
                   behind = p - obs.shape.support(nrm, &hint_obs[1]);
      const double e_ahead = link.extent(nrm, &hint_link[0]), e_behind = link.extent(-nrm, &hint_link[1]);
      return ahead - e_ahead >= behind - e_behind ? separated_on(nrm, ahead, e_ahead)
                                                  : separated_on(-nrm, behind, e_behind);
    };
    auto standard_axes = [&] {
      bool sep = false;
      for (int k = 0; k < 3 && !sep; ++k) sep = try_axis(obs.box.rotation.col(k));
      for (int k = 0; k < 3 && !sep; ++k) sep = try_axis(box.rotation.col(k));
      for (int k = 0; k < 3 && !sep; ++k)
        for (int l = 0; l < 3 && !sep; ++l)
          sep = try_axis(box.rotation.col(k).cross(obs.box.rotation.col(l)));
      return sep || try_axis(diff);
    };
    bool sep = standard_axes();
    if (!sep && !boxes) {
      on_boxes = false;
      // GJK ends at the two shapes' nearest vertices: the axes' supports toward each other climb
      // from there, the supports away from each other from where the last such climb ended.
      sep = try_axis(convex_distance(link.shape(), obs.shape, 1e-6, &hint_link[0], &hint_obs[0]).axis) ||
            standard_axes();
    }
    out.separated = sep;
  }
  out.gap = best_gap;
  return out;
}

int blame(const SweptLink& link, const Eigen::Vector3d& axis, const Eigen::VectorXd& weights,
          const SweepBound* bound) {
  const LinkChain& chain = link.link();
  int best = -1;
  double best_contribution = 0;
  for (size_t p = static_cast<size_t>(link.held()); p < chain.joints.size(); ++p) {
    const double w = weights[chain.joints[p]];
    const double contribution = bound ? bound->contribution(link, p, w) : link.contribution(axis, p, w);
    if (contribution > best_contribution) {
      best_contribution = contribution;
      best = chain.joints[p];
    }
  }
  return best;
}

}  // namespace leeway
