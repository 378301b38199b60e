#include "leeway/core/kinematics.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Dense>

#include "leeway/core/box.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/shape.hpp"
#include "random.hpp"

namespace leeway {
namespace {

// Damped-least-squares (Levenberg-Marquardt) settings of solve_ik. The damping lambda adapts: it
// shrinks after a step that lowers the residual and grows after one that does not, within
// [kMinDamping, kMaxDamping]; the run stops when the damping is at its maximum and the step has
// vanished (a local minimum).
constexpr double kInitialDamping = 1e-2;  // lambda at every start
constexpr double kMinDamping = 1e-4;      // floor: keeps J J^T + lambda^2 I well conditioned
constexpr double kMaxDamping = 1.0;       // ceiling: at 1 the step is a short gradient step
constexpr double kDampingDecrease = 0.5;  // lambda *= this after an accepted step
constexpr double kDampingIncrease = 4.0;  // lambda *= this after a rejected step
// Largest change of any joint in one iteration [rad or m]: the Jacobian is linear only nearby.
constexpr double kMaxJointStep = 0.3;
// A step this small [rad or m] with maximal damping means no further progress.
constexpr double kStalledStep = 1e-9;

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

}  // namespace

void update_robot_kinematics(const Scene& scene, mjData& d) {
  // MuJoCo 2.2's mj_kinematics (engine_core_smooth.c) restricted to the moving bodies, whose
  // parents come first (MuJoCo's body order). Omitted because they cannot apply here: free joints,
  // ball joints and qpos quaternions (Scene accepts hinge and slide joints only), mocap bodies
  // (children of the world without joints, so never moving).
  const mjModel& m = scene.model();
  mjtNum pos[3], quat[4], qloc[4], qtmp[4], vec[3], vec1[3], xanchor[3], xaxis[3];
  for (int i : scene.moving_bodies()) {
    const int pid = m.body_parentid[i];
    mju_rotVecMat(vec, m.body_pos + 3 * i, d.xmat + 9 * pid);
    mju_add3(pos, d.xpos + 3 * pid, vec);
    mju_mulQuat(quat, d.xquat + 4 * pid, m.body_quat + 4 * i);
    for (int j = 0; j < m.body_jntnum[i]; ++j) {
      const int jid = m.body_jntadr[i] + j;
      const int qadr = m.jnt_qposadr[jid];
      mju_rotVecQuat(xaxis, m.jnt_axis + 3 * jid, quat);
      mju_rotVecQuat(xanchor, m.jnt_pos + 3 * jid, quat);
      mju_addTo3(xanchor, pos);
      if (m.jnt_type[jid] == mjJNT_SLIDE) {
        mju_addToScl3(pos, xaxis, d.qpos[qadr] - m.qpos0[qadr]);
      } else {  // hinge
        mju_axisAngle2Quat(qloc, m.jnt_axis + 3 * jid, d.qpos[qadr] - m.qpos0[qadr]);
        mju_mulQuat(qtmp, quat, qloc);
        mju_copy4(quat, qtmp);
        // Off-centre rotation: the anchor stays where it was.
        mju_sub3(vec, xanchor, pos);
        mju_rotVecQuat(vec1, m.jnt_pos + 3 * jid, quat);
        for (int k = 0; k < 3; ++k) pos[k] += (vec[k] - vec1[k]);
      }
      mju_copy3(d.xanchor + 3 * jid, xanchor);
      mju_copy3(d.xaxis + 3 * jid, xaxis);
    }
    mju_normalize4(quat);
    mju_copy4(d.xquat + 4 * i, quat);
    mju_copy3(d.xpos + 3 * i, pos);
    mju_quat2Mat(d.xmat + 9 * i, quat);
  }
  for (int i : scene.moving_bodies())
    mj_local2Global(&d, d.xipos + 3 * i, d.ximat + 9 * i, m.body_ipos + 3 * i, m.body_iquat + 4 * i, i,
                    m.body_sameframe[i]);
  for (int g : scene.moving_geoms())
    mj_local2Global(&d, d.geom_xpos + 3 * g, d.geom_xmat + 9 * g, m.geom_pos + 3 * g, m.geom_quat + 4 * g,
                    m.geom_bodyid[g], m.geom_sameframe[g]);
  for (int s : scene.moving_sites())
    mj_local2Global(&d, d.site_xpos + 3 * s, d.site_xmat + 9 * s, m.site_pos + 3 * s, m.site_quat + 4 * s,
                    m.site_bodyid[s], m.site_sameframe[s]);
}

RobotState::RobotState(const Scene& scene) : scene_(&scene), data_(make_data(scene.model())) {
  // Idempotent; documented at install_mujoco_error_handlers(): MuJoCo must throw, not exit().
  install_mujoco_error_handlers();
  // Once over everything (the obstacles' poses); set() then updates the moving part only.
  mj_kinematics(&scene.model(), data_.get());
}

void RobotState::set(const Eigen::VectorXd& q) {
  scene_->validate_configuration(q, "configuration");
  scene_->set_qpos(*data_, q);
  update_robot_kinematics(*scene_, *data_);
}

Pose RobotState::site_pose(int site) const {
  Pose p;
  p.position = Eigen::Map<const Eigen::Vector3d>(data_->site_xpos + 3 * site);
  p.rotation = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(data_->site_xmat + 9 * site);
  return p;
}

Pose RobotState::tool_pose() const { return site_pose(scene_->tool_site()); }

void RobotState::run_collision() {
  prevent_contact_warnings(*data_);  // a full contact buffer still answers "in collision"
  mj_collision(&scene_->model(), data_.get());
}

bool RobotState::in_collision(const Eigen::VectorXd& q) { return obstacle_contact(q) || self_contact() >= 0; }

int RobotState::self_contact() const {
  const mjModel& m = scene_->model();
  const std::vector<RobotPair>& pairs = scene_->self_pairs();
  for (size_t i = 0; i < pairs.size(); ++i)
    if (geoms_touch(m, *data_, pairs[i].geom1, pairs[i].geom2)) return static_cast<int>(i);
  return -1;
}

std::vector<SelfContact> RobotState::self_contacts(const Eigen::VectorXd& q) {
  set(q);
  const mjModel& m = scene_->model();
  std::vector<SelfContact> out;
  for (const RobotPair& p : scene_->self_pairs()) {
    if (!geoms_touch(m, *data_, p.geom1, p.geom2)) continue;
    SelfContact c{p.geom1, p.geom2, 0.0};
    if (m.geom_type[p.geom1] == mjGEOM_BOX && m.geom_type[p.geom2] == mjGEOM_BOX) {
      c.depth = std::max(0.0, box_penetration(geom_box(m, *data_, p.geom1), geom_box(m, *data_, p.geom2)));
    } else {
      int g1 = p.geom1, g2 = p.geom2;
      if (m.geom_type[g1] > m.geom_type[g2]) std::swap(g1, g2);
      mjContact con[mjMAXCONPAIR];
      const int n = mjCOLLISIONFUNC[m.geom_type[g1]][m.geom_type[g2]](
          &m, data_.get(), con, g1, g2, std::max(m.geom_margin[g1], m.geom_margin[g2]));
      for (int k = 0; k < n; ++k) c.depth = std::max(c.depth, -static_cast<double>(con[k].dist));
    }
    out.push_back(c);
  }
  std::sort(out.begin(), out.end(),
            [](const SelfContact& a, const SelfContact& b) { return a.depth > b.depth; });
  return out;
}

std::vector<SelfContact> self_contacts_within(RobotState& state, const Eigen::VectorXd& q, double tolerance) {
  std::vector<SelfContact> out = state.self_contacts(q);
  const mjModel& m = state.scene().model();
  for (const RobotPair& p : state.scene().self_pairs()) {
    if (m.geom_type[p.geom1] == mjGEOM_PLANE || m.geom_type[p.geom2] == mjGEOM_PLANE) continue;
    if (std::any_of(out.begin(), out.end(),
                    [&](const SelfContact& c) { return c.geom1 == p.geom1 && c.geom2 == p.geom2; }))
      continue;
    if (shape_distance(geom_shape(m, state.data(), p.geom1), geom_shape(m, state.data(), p.geom2)) <=
        tolerance)
      out.push_back({p.geom1, p.geom2, 0.0});
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const SelfContact& a, const SelfContact& b) { return a.depth > b.depth; });
  return out;
}

bool RobotState::obstacle_contact(const Eigen::VectorXd& q) {
  set(q);
  const mjModel& m = scene_->model();
  if (scene_->checker() == CollisionChecker::kMidphase)
    return any_contact(m, *data_, scene_->link_geoms(), scene_->statics());
  run_collision();
  return data_->ncon > 0;
}

std::vector<Contact> RobotState::contacts(const Eigen::VectorXd& q) {
  set(q);
  run_collision();
  std::vector<Contact> out;
  for (int i = 0; i < data_->ncon; ++i) {
    const mjContact& c = data_->contact[i];
    Contact k;
    const bool first_is_link = scene_->role(c.geom1) == GeomRole::kLink;
    k.link_geom = first_is_link ? c.geom1 : c.geom2;
    k.obstacle_geom = first_is_link ? c.geom2 : c.geom1;
    const mjModel& m = scene_->model();
    if (m.geom_type[c.geom1] == mjGEOM_BOX && m.geom_type[c.geom2] == mjGEOM_BOX)
      k.depth = std::max(0.0, box_penetration(geom_box(m, *data_, c.geom1), geom_box(m, *data_, c.geom2)));
    else
      k.depth = std::max(0.0, -static_cast<double>(c.dist));
    // Several contact points of one geom pair: keep the deepest.
    auto same = std::find_if(out.begin(), out.end(), [&](const Contact& o) {
      return o.link_geom == k.link_geom && o.obstacle_geom == k.obstacle_geom;
    });
    if (same == out.end())
      out.push_back(k);
    else
      same->depth = std::max(same->depth, k.depth);
  }
  std::sort(out.begin(), out.end(), [](const Contact& a, const Contact& b) { return a.depth > b.depth; });
  return out;
}

Clearance RobotState::clearance(const Eigen::VectorXd& q) {
  set(q);
  const mjModel& m = scene_->model();
  Clearance best;
  for (int o : scene_->obstacle_geoms()) {
    if (!has_bounding_box(m, o)) continue;  // the plane rule, box.hpp
    const Shape ob = geom_shape(m, *data_, o);
    for (int l : scene_->link_geoms()) {
      const double dist = shape_distance(geom_shape(m, *data_, l), ob);
      if (dist < best.distance) best = {dist, l, o};
    }
  }
  return best;
}

Eigen::MatrixXd RobotState::tool_jacobian() {
  const mjModel& m = scene_->model();
  mj_comPos(&m, data_.get());
  std::vector<mjtNum> jacp(static_cast<size_t>(3 * m.nv)), jacr(static_cast<size_t>(3 * m.nv));
  mj_jacSite(&m, data_.get(), jacp.data(), jacr.data(), scene_->tool_site());
  Eigen::MatrixXd j(6, scene_->dof());
  for (int i = 0; i < scene_->dof(); ++i) {
    const int dof = m.jnt_dofadr[scene_->joints()[static_cast<size_t>(i)].id];
    for (int r = 0; r < 3; ++r) {
      j(r, i) = jacp[static_cast<size_t>(r * m.nv + dof)];
      j(r + 3, i) = jacr[static_cast<size_t>(r * m.nv + dof)];
    }
  }
  return j;
}

Eigen::VectorXd default_ik_seed(const Scene& scene) {
  if (!scene.keyframes().empty()) return scene.keyframes().front().q;
  return Eigen::VectorXd::Zero(scene.dof()).cwiseMax(scene.lower_limits()).cwiseMin(scene.upper_limits());
}

IkResult solve_ik(RobotState& state, const Eigen::Vector3d& target, const Eigen::VectorXd& seed,
                  const IkOptions& options) {
  const Scene& scene = state.scene();
  scene.validate_configuration(seed, "IK seed");
  if (!target.allFinite()) throw InputError("IK target position is not finite");
  const int n = scene.dof();
  const Eigen::VectorXd lo = scene.lower_limits(), hi = scene.upper_limits();
  std::vector<bool> locked = options.locked;
  locked.resize(static_cast<size_t>(n), false);
  const Eigen::Vector3d down(0, 0, -1);

  auto residual = [&](Eigen::VectorXd& r) {
    const Pose p = state.tool_pose();
    r.resize(options.tool_down ? 6 : 3);
    r.head<3>() = p.position - target;
    if (options.tool_down) r.tail<3>() = p.rotation.col(2) - down;
  };

  std::mt19937_64 rng(options.seed);
  IkResult best;
  best.q = seed.cwiseMax(lo).cwiseMin(hi);
  double best_cost = INFINITY;
  double best_distance = INFINITY;
  for (int start = 0; start <= options.restarts; ++start) {
    Eigen::VectorXd q = seed.cwiseMax(lo).cwiseMin(hi);
    if (start > 0)
      for (int i = 0; i < n; ++i)
        if (!locked[static_cast<size_t>(i)]) q[i] = lo[i] + (hi[i] - lo[i]) * detail::unit(rng);
    Eigen::VectorXd r;
    double lambda = kInitialDamping;
    state.set(q);
    residual(r);
    for (int it = 0; it < options.max_iterations; ++it) {
      if (r.head<3>().norm() < options.position_tolerance &&
          (!options.tool_down || r.tail<3>().norm() < options.orientation_tolerance))
        break;
      Eigen::MatrixXd jac = state.tool_jacobian();
      Eigen::MatrixXd j(r.size(), n);
      j.topRows<3>() = jac.topRows<3>();
      if (options.tool_down)
        j.bottomRows<3>() = -skew(state.tool_pose().rotation.col(2)) * jac.bottomRows<3>();
      for (int i = 0; i < n; ++i)
        if (locked[static_cast<size_t>(i)]) j.col(i).setZero();
      const Eigen::MatrixXd a =
          j * j.transpose() + lambda * lambda * Eigen::MatrixXd::Identity(r.size(), r.size());
      Eigen::VectorXd dq = -j.transpose() * a.ldlt().solve(r);
      const double step = dq.cwiseAbs().maxCoeff();
      if (step > kMaxJointStep) dq *= kMaxJointStep / step;
      const Eigen::VectorXd q_new = (q + dq).cwiseMax(lo).cwiseMin(hi);
      state.set(q_new);
      Eigen::VectorXd r_new;
      residual(r_new);
      if (r_new.norm() < r.norm()) {
        q = q_new;
        r = r_new;
        lambda = std::max(kMinDamping, lambda * kDampingDecrease);
      } else {
        lambda = std::min(kMaxDamping, lambda * kDampingIncrease);
        state.set(q);
        if (lambda >= kMaxDamping && step < kStalledStep) break;
      }
    }
    state.set(q);
    const double pos_err = r.head<3>().norm();
    const double ori_err = options.tool_down ? r.tail<3>().norm() : 0.0;
    const bool converged = pos_err < options.position_tolerance &&
                           (!options.tool_down || ori_err < options.orientation_tolerance);
    const bool ok = converged && (!options.require_collision_free || !state.in_collision(q));
    const double distance = (q - seed).norm();
    if (ok) {
      ++best.solutions_found;
      if (!best.success || distance < best_distance) {
        best.success = true;
        best.q = q;
        best.position_error = pos_err;
        best.orientation_error = ori_err;
        best_distance = distance;
      }
    } else if (!best.success && pos_err + ori_err < best_cost) {
      best_cost = pos_err + ori_err;
      best.q = q;
      best.position_error = pos_err;
      best.orientation_error = ori_err;
    }
  }
  state.set(best.q);
  return best;
}

}  // namespace leeway
