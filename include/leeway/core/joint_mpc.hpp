#pragma once
//! @file joint_mpc.hpp
//! A receding-horizon controller for one joint: over the next N stages (the first one control
//! period long, the others `period`) it
//! chooses piecewise-constant accelerations that follow a reference while keeping the position
//! inside a box per stage, the speed within +-v_max and the acceleration within +-a_max. The bounds
//! are boxes per joint and the cost is a sum over joints, so an n-joint MPC is n independent
//! problems of this size (docs/simulate.md, "Controller").
//!
//! Each problem is a small dense QP, solved by ADMM (the operator splitting of OSQP) with a
//! matrix inverted once per horizon and a fixed iteration count: no allocation per solve, the
//! same work every period, and the same answer for the same input.

#include <Eigen/Core>

namespace leeway {

//! The horizon, the limits and the weights of JointMpc.
struct JointMpcOptions {
  int horizon = 12;            //!< N: stages [1, 200]
  double first_period = 0.04;  //!< length of stage 0 [s]
  double period = 0.04;        //!< length of stages 1 .. N-1 [s]
  double max_speed = 1.0;      //!< v_max [rad/s or m/s]
  double max_accel = 4.0;      //!< a_max [rad/s^2 or m/s^2]
  double tracking_weight = 1;  //!< per stage, on (q_k - r_k)^2 [1/rad^2]
  //! per stage, on a_k^2, relative to tracking_weight [s^4]: 1e-4 makes 0.1 rad/s^2 cost as much
  //! as 1 mrad of tracking error.
  double accel_weight = 1e-4;
  int iterations = 100;  //!< ADMM iterations per solve
};

//! The plan of one solve: accelerations a_0 .. a_{N-1} and the positions q_1 .. q_N and speeds
//! v_1 .. v_N they give from (q_0, v_0).
struct JointPlan {
  Eigen::VectorXd accel;
  Eigen::VectorXd position;
  Eigen::VectorXd speed;
  //! Largest violation of a constraint by the plan [rad, rad/s or rad/s^2, each as is]: 0 when the
  //! plan meets every bound, small (ADMM's tolerance) near one, large when the bounds cannot be met
  //! from (q_0, v_0) (then the plan is the least-squares compromise ADMM reaches).
  double violation = 0;
};

//! The controller for one joint. Immutable after construction except for its warm start.
class JointMpc {
 public:
  //! @throws InputError when an option is out of its range.
  explicit JointMpc(const JointMpcOptions& options);

  const JointMpcOptions& options() const { return options_; }

  //! Solves for the next N stages from position q0 and speed v0: reference r (N values, r_k for
  //! stage k = 1..N), position bounds lower/upper (N values each, lower <= upper). The previous
  //! solve's plan, shifted by a stage, is the warm start.
  JointPlan solve(double q0, double v0, const Eigen::VectorXd& reference, const Eigen::VectorXd& lower,
                  const Eigen::VectorXd& upper);

  //! Forgets the warm start.
  void reset();

 private:
  JointMpcOptions options_;
  Eigen::VectorXd stage_end_;  // t_k: the end of stage k - 1 [s] after the start
  Eigen::MatrixXd phi_q_;      // q_k - q0 - t_k v0 = (phi_q_ x)_k
  Eigen::MatrixXd phi_v_;      // v_k - v0 = (phi_v_ x)_k
  Eigen::MatrixXd a_;          // constraint rows [phi_q; phi_v; I], each scaled to unit norm
  Eigen::VectorXd row_scale_;
  Eigen::MatrixXd kkt_inverse_;  // (P + sigma I + rho A^T A)^-1: small, so one product per iteration
  double cost_scale_ = 1;        // P's largest diagonal value before scaling
  double rho_ = 0, sigma_ = 0;
  // Warm start (x: accelerations, z and y: constraint values and multipliers).
  Eigen::VectorXd x_, z_, y_;
  bool warm_ = false;
};

}  // namespace leeway
