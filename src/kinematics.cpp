#include "leeway/kinematics.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Dense>

#include "leeway/box.hpp"
#include "leeway/error.hpp"
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

RobotState::RobotState(const Scene& scene) : scene_(&scene), data_(make_data(scene.model())) {
  // Idempotent; documented at install_mujoco_error_handlers(): MuJoCo must throw, not exit().
  install_mujoco_error_handlers();
}

void RobotState::set(const Eigen::VectorXd& q) {
  scene_->validate_configuration(q, "configuration");
  scene_->set_qpos(*data_, q);
  mj_kinematics(&scene_->model(), data_.get());
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

bool RobotState::in_collision(const Eigen::VectorXd& q) {
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
    const Box ob = geom_box(m, *data_, o);
    for (int l : scene_->link_geoms()) {
      const double dist = box_distance(geom_box(m, *data_, l), ob);
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
