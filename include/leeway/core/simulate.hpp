#pragma once
//! @file simulate.hpp
//! The closed loop: MuJoCo's physics of the robot in its cell, a simulated co-worker pushing the
//! tool, an admittance law turning the push into a wish to move, and a controller that follows the
//! nominal path while keeping the commanded configuration inside the bounds (docs/simulate.md).

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "leeway/core/bounds_trajectory.hpp"
#include "leeway/core/joint_mpc.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {

//! One sample of a recorded push: the wrench at the tool site, in world axes.
struct WrenchSample {
  double t = 0;                                      //!< [s]
  Eigen::Vector3d force = Eigen::Vector3d::Zero();   //!< [N]
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();  //!< [N m]
};

//! Reads a push file: one sample per line, `t fx fy fz [tx ty tz]` separated by commas or spaces;
//! lines starting with '#' and a first line that is not numbers (a header) are skipped.
//! @throws InputError naming the file, line and value on a missing file, a value that is not a
//! finite number, a force over 10 kN or a torque over 10 kN m, or times that do not increase.
std::vector<WrenchSample> read_wrench_file(const std::string& path);

//! How the simulated co-worker pushes the tool.
enum class HumanKind {
  kNone,        //!< no push: the robot follows the nominal path
  kRandom,      //!< a smooth random force, seeded
  kPushToward,  //!< a force from the tool toward an obstacle's nearest point
  kFile,        //!< a recorded wrench (read_wrench_file)
};

//! The co-worker's model.
struct HumanOptions {
  HumanKind kind = HumanKind::kRandom;
  //! kRandom: the standard deviation of each force component; kPushToward: the force's magnitude
  //! [N]. [0, 2000]
  double amplitude = 60;
  //! kRandom: the corner frequency of the low-pass filters that shape white noise into the force
  //! [Hz]. (0, 20]
  double bandwidth = 0.5;
  //! kPushToward: an obstacle geom's or body's name, or "nearest" (the obstacle geom nearest the
  //! tool at each moment).
  std::string target;
  //! kFile: the samples (linear between them, zero before the first and after the last).
  std::vector<WrenchSample> samples;
};

//! Which controller keeps the command inside the bounds.
enum class ControllerKind {
  kMpc,         //!< JointMpc per joint over a horizon (the default)
  kProjection,  //!< the baseline: the admitted target clamped into the box, then rate-limited
};

//! Everything simulate() needs besides the scene and the bounds. Defaults are documented in
//! docs/simulate.md; check() gives their ranges.
struct SimulateOptions {
  HumanOptions human;
  std::uint64_t seed = 1;  //!< the random push's stream
  //! Progress along the path relative to the nominal timing (1: the nominal speed). (0, 10]
  double speed = 1.0;
  ControllerKind controller = ControllerKind::kMpc;
  double control_period = 0.01;  //!< the controller's period [s]: a multiple of the model's timestep
  //! The MPC's horizon and weights (its limits come from speed_scale and max_accel below).
  JointMpcOptions mpc;
  //! Admittance per joint: inertia [kg m^2 or kg] and damping [N m s/rad or N s/m] of
  //! M qdd + D qd = J^T w.
  double admittance_inertia = 10;
  double admittance_damping = 150;
  //! Speed limit of a joint: speed_scale times its nominal speed (joint user[0]); joints without
  //! one get default_speed [rad/s or m/s].
  double speed_scale = 2.0;
  double default_speed = 1.0;
  double max_accel = 4.0;  //!< acceleration limit of every joint [rad/s^2 or m/s^2]
  //! The push against the tool's direction of travel that stops progress along the path [N];
  //! progress slows linearly from no push to this one.
  double hold_force = 80;
  //! How far inside the bounds the controller plans [rad or m] (at most a quarter of a bound's width).
  double plan_margin = 1e-3;
  //! Distances up to this are measured [m]; farther ones are reported as "at least this".
  double distance_range = 0.5;
  double end_hold = 2.0;  //!< simulated time after the path's end is reached [s]
  //! Longest simulated time [s]; 0: 3 x the nominal duration / speed + end_hold + 5 s.
  double max_time = 0;

  //! @throws InputError naming the option and value when one is out of its range.
  void check() const;
};

//! A contact seen during the run (MuJoCo's: dist < 0 between a robot geom and the cell, or between
//! two robot geoms of a counted self pair).
struct SimContact {
  double t = 0;  //!< [s]
  std::string geom1, geom2;
  double depth = 0;   //!< penetration [m]
  bool self = false;  //!< two robot geoms
};

//! One video frame's worth of state, handed to the frame callback.
struct SimFrame {
  double t = 0;                                     //!< simulated time [s]
  double s = 0;                                     //!< path parameter
  Eigen::Vector3d tool = Eigen::Vector3d::Zero();   //!< tool site position [m]
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  //!< the human's force [N]
  BoundsStage box;                                  //!< the bounds at s
};

//! What a run measured.
struct SimulationReport {
  double simulated_time = 0;           //!< [s]
  long steps = 0;                      //!< physics steps
  double timestep = 0;                 //!< the model's [s]
  bool reached_end = false;            //!< progress reached the last waypoint
  double end_time = 0;                 //!< when it did [s] (or the run's end)
  double nominal_duration = 0;         //!< the bounds' nominal duration [s]
  std::vector<double> waypoint_times;  //!< when progress first reached each waypoint [s]; NaN never

  long contact_steps = 0;  //!< steps with a contact
  std::optional<SimContact> first_contact;
  double min_distance = 0;  //!< smallest robot-cell or counted robot-robot distance [m]
  std::string min_distance_geom1, min_distance_geom2;
  double min_distance_t = 0;
  bool min_distance_capped = false;  //!< nothing came within distance_range

  bool left_bounds = false;  //!< the robot's configuration was ever outside the box at its s
  double max_excursion = 0;  //!< the most it was [rad or m] (0 when it never was)
  long clamp_steps = 0;      //!< steps where the safety clamp moved the command into the box
  long limit_steps = 0;      //!< control periods whose command broke the speed or acceleration limit
  //! The largest |a| / a_max or |v| / v_max of the command over the control periods (over 1: a
  //! limit was broken, by that factor).
  double max_limit_ratio = 0;
  //! Per joint: the largest share of the room between nominal and bound (on the side it moved to)
  //! that the robot used, in [0, 1].
  Eigen::VectorXd freedom_used;
  Eigen::VectorXd max_deviation;  //!< per joint: largest |q - nominal(s)| [rad or m]
  double max_tracking_error = 0;  //!< largest |q - command| over joints and steps [rad or m]
  double rms_force = 0;           //!< the push's RMS magnitude [N]
  double max_force = 0;           //!< its largest magnitude [N]
  double wall_time = 0;           //!< [s]
};

//! Called at every control period with the state; a video writer keeps every n-th.
using FrameCallback = std::function<void(const mjModel&, const mjData&, const SimFrame&)>;

//! Runs the closed loop on a copy of the scene's model (the scene is not changed) along `bounds`,
//! which must be the scene's (same joints). Deterministic: the same inputs and seed give the same
//! report (wall_time aside).
//! @throws InputError on options out of range (SimulateOptions::check), a push target that names
//! no obstacle, or a model timestep that does not divide the control period.
SimulationReport simulate(const Scene& scene, const BoundsTrajectory& bounds, const SimulateOptions& options,
                          const FrameCallback& on_frame = {});

//! The report as JSON ("format": "leeway-simulation-1"), with the options that produced it: `cell`
//! and `bounds` name the inputs.
nlohmann::json simulation_json(const Scene& scene, const SimulationReport& report,
                               const SimulateOptions& options, const std::string& cell,
                               const std::string& bounds);

//! "random", "push-toward", "file" or "none".
const char* human_kind_name(HumanKind kind);

}  // namespace leeway
