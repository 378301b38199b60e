#include "leeway/core/joint_mpc.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <string>

#include "leeway/core/error.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {

namespace {

void require_range(double value, double low, double high, const char* name, const char* unit) {
  if (!(value >= low && value <= high))
    throw InputError(std::string("controller option ") + name + " " + format_number(value) + " is outside [" +
                     format_number(low) + ", " + format_number(high) + "] " + unit);
}

// ADMM's over-relaxation, as OSQP's default.
constexpr double kAlpha = 1.6;

}  // namespace

JointMpc::JointMpc(const JointMpcOptions& options) : options_(options) {
  require_range(options.horizon, 1, 200, "horizon", "stages");
  require_range(options.period, 1e-4, 1.0, "period", "s");
  require_range(options.first_period, 1e-4, 1.0, "first_period", "s");
  require_range(options.max_speed, 1e-6, 1e3, "max_speed", "rad/s or m/s");
  require_range(options.max_accel, 1e-6, 1e4, "max_accel", "rad/s^2 or m/s^2");
  require_range(options.tracking_weight, 1e-9, 1e9, "tracking_weight", "1/rad^2");
  require_range(options.accel_weight, 0, 1e9, "accel_weight", "s^4");
  require_range(options.iterations, 1, 100000, "iterations", "");

  const int n = options.horizon;
  // Stage 0 lasts first_period (the control period: the next solve starts where it ends), the
  // others period. With constant acceleration a_j over stage j of length d_j, ending at t_{j+1}:
  // q_k = q0 + t_k v0 + sum_{j<k} a_j d_j (t_k - t_{j+1} + d_j / 2) and v_k = v0 + sum_{j<k} a_j d_j.
  // The variables are x = a / a_max, so that every |x_j| <= 1.
  stage_end_ = Eigen::VectorXd(n);
  for (int k = 0; k < n; ++k)
    stage_end_[k] = (k == 0 ? 0.0 : stage_end_[k - 1]) + (k == 0 ? options.first_period : options.period);
  phi_q_ = Eigen::MatrixXd::Zero(n, n);
  phi_v_ = Eigen::MatrixXd::Zero(n, n);
  for (int k = 1; k <= n; ++k)
    for (int j = 0; j < k; ++j) {
      const double d = j == 0 ? options.first_period : options.period;
      phi_q_(k - 1, j) = d * (stage_end_[k - 1] - stage_end_[j] + d / 2) * options.max_accel;
      phi_v_(k - 1, j) = d * options.max_accel;
    }
  a_.resize(3 * n, n);
  a_ << phi_q_, phi_v_, Eigen::MatrixXd::Identity(n, n);
  row_scale_ = a_.rowwise().norm().cwiseInverse();
  a_ = row_scale_.asDiagonal() * a_;

  // P of the cost sum_k w (q_k - r_k)^2 + w c a_k^2, divided by its largest diagonal value so that
  // one rho suits every horizon and period.
  Eigen::MatrixXd p = phi_q_.transpose() * phi_q_;
  p.diagonal().array() += options.accel_weight * options.max_accel * options.max_accel;
  cost_scale_ = p.diagonal().maxCoeff();
  p /= cost_scale_;
  rho_ = 1;
  sigma_ = 1e-6;
  Eigen::MatrixXd kkt = p + sigma_ * Eigen::MatrixXd::Identity(n, n) + rho_ * a_.transpose() * a_;
  kkt_inverse_ = kkt.llt().solve(Eigen::MatrixXd::Identity(n, n));
  reset();
}

void JointMpc::reset() {
  const int n = options_.horizon;
  x_ = Eigen::VectorXd::Zero(n);
  z_ = Eigen::VectorXd::Zero(3 * n);
  y_ = Eigen::VectorXd::Zero(3 * n);
  warm_ = false;
}

JointPlan JointMpc::solve(double q0, double v0, const Eigen::VectorXd& reference,
                          const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  const int n = options_.horizon;
  Eigen::VectorXd free_q = Eigen::VectorXd::Constant(n, q0) + v0 * stage_end_;
  const Eigen::VectorXd free_v = Eigen::VectorXd::Constant(n, v0);

  // The linear term of the scaled cost: phi_q^T (free_q - r), scaled as P was.
  const Eigen::VectorXd q_lin = phi_q_.transpose() * (free_q - reference) / cost_scale_;

  Eigen::VectorXd lo(3 * n), hi(3 * n);
  lo << lower - free_q, Eigen::VectorXd::Constant(n, -options_.max_speed) - free_v,
      Eigen::VectorXd::Constant(n, -1);
  hi << upper - free_q, Eigen::VectorXd::Constant(n, options_.max_speed) - free_v,
      Eigen::VectorXd::Constant(n, 1);
  lo.array() *= row_scale_.array();
  hi.array() *= row_scale_.array();

  if (warm_) {
    // Shift by one stage: the previous plan's stage k + 1 is this one's stage k.
    for (int k = 0; k + 1 < n; ++k) x_[k] = x_[k + 1];
  }
  Eigen::VectorXd x = x_;
  Eigen::VectorXd z = (a_ * x).cwiseMax(lo).cwiseMin(hi);
  Eigen::VectorXd y = warm_ ? y_ : Eigen::VectorXd::Zero(3 * n);
  Eigen::VectorXd rhs(n), x_tilde(n), z_tilde(3 * n), z_relaxed(3 * n);
  for (int it = 0; it < options_.iterations; ++it) {
    rhs.noalias() = sigma_ * x - q_lin;
    rhs.noalias() += a_.transpose() * (rho_ * z - y);
    x_tilde.noalias() = kkt_inverse_ * rhs;
    z_tilde.noalias() = a_ * x_tilde;
    x = kAlpha * x_tilde + (1 - kAlpha) * x;
    z_relaxed = kAlpha * z_tilde + (1 - kAlpha) * z;
    const Eigen::VectorXd z_next = (z_relaxed + y / rho_).cwiseMax(lo).cwiseMin(hi);
    y += rho_ * (z_relaxed - z_next);
    z = z_next;
  }
  x_ = x;
  y_ = y;
  warm_ = true;

  JointPlan plan;
  plan.accel = options_.max_accel * x;
  plan.position = free_q + phi_q_ * x;
  plan.speed = free_v + phi_v_ * x;
  double violation = 0;
  for (int k = 0; k < n; ++k) {
    violation = std::max({violation, lower[k] - plan.position[k], plan.position[k] - upper[k],
                          std::abs(plan.speed[k]) - options_.max_speed,
                          std::abs(plan.accel[k]) - options_.max_accel});
  }
  plan.violation = violation;
  return plan;
}

}  // namespace leeway
