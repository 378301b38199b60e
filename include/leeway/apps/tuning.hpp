#pragma once
//! @file tuning.hpp
//! Automated tuning of the height-function parameters (the thesis tuned them "through
//! trial and error", section 4.1): tuning cases, the tuned variables and their bounds, one
//! evaluation of a parameter set on a case, the deterministic time proxy and the objective.
//! The optimiser loop (NLopt) is in tuning/; docs/tuning.md describes every choice.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "leeway/core/box.hpp"
#include "leeway/core/params.hpp"
#include "leeway/core/pipeline.hpp"
#include "leeway/core/scene.hpp"
#include "leeway/core/volume_world.hpp"

namespace leeway {

//! A (cell, path) case as given on the command line: "CELL.xml:FROM:TO".
struct CaseSpec {
  std::string cell;  //!< MJCF file of the workcell
  std::string from;  //!< keyframe the path starts at
  std::string to;    //!< keyframe the path ends at
  //! "dallara:home:patch": the cell's file stem and the two keyframes.
  std::string label() const;
};

//! Splits "CELL.xml:FROM:TO" at its last two colons. @throws InputError quoting the text when a
//! part is missing or empty.
CaseSpec parse_case(const std::string& text);

//! A case loaded and ready to evaluate: the scene, the joint-linear path between the keyframes, the
//! cell's parameters (defaults, the cell's MJCF custom numerics, then the user's base file) and one
//! volume pool reused by every evaluation. Owns its Scene and VolumeModel (the model points into the
//! scene; both live as long as the case).
class TuningCase {
 public:
  //! Loads the cell and the path. `base_json` (null for none) is applied on top of the cell's
  //! defaults as `leeway bounds --params` does; `pool_capacity` is the largest MAX_cells evaluated.
  //! @throws InputError naming the case and the problem (missing file, unknown keyframe, a path
  //! outside the joint limits, invalid base parameters).
  TuningCase(const CaseSpec& spec, const nlohmann::json& base_json, int waypoints, int pool_capacity,
             const SceneOptions& options = {});
  //! The case as given.
  const CaseSpec& spec() const { return spec_; }
  //! The loaded cell.
  const Scene& scene() const { return *scene_; }
  //! The joint-linear path between the two keyframes.
  const std::vector<Eigen::VectorXd>& path() const { return path_; }
  //! Defaults, then the cell's custom numerics, then the base file's keys.
  const Params& cell_params() const { return params_; }
  //! The volume pool, reused by every evaluation (compute_bounds re-injects each volume).
  VolumeModel& world() { return *world_; }

 private:
  CaseSpec spec_;
  std::unique_ptr<Scene> scene_;
  std::vector<Eigen::VectorXd> path_;
  Params params_;
  std::unique_ptr<VolumeModel> world_;
};

//! One tuned variable: a parameter of section 4.1 (or leeway's trail margin) with its bounds.
struct TunedVariable {
  std::string name;   //!< the parameter key without its section ("d_t_lb"), or "log10_max_cells"
  double lower = 0;   //!< bound given to NLopt
  double upper = 0;   //!< bound given to NLopt
  double thesis = 0;  //!< the thesis's value (section 4.1; MAX_cells: leeway's default 20000)
  std::string unit;   //!< "m", "-" or "log10 cells"
};

//! The tuned variables, in order: d_t_lb, d_t_ub, d_g_lb, d_g_ub, d_ng_ub, h_max, alpha_t, alpha_g,
//! alpha_ng, log10_max_cells, trail_margin (docs/tuning.md gives the bounds and why).
std::vector<TunedVariable> tuned_variables();

//! Index of log10_max_cells in tuned_variables().
inline constexpr size_t kMaxCellsVariable = 9;

//! Smallest gap UB - LB [m] that the constraints d_t_lb - d_t_ub + gap <= 0 and
//! d_g_lb - d_g_ub + gap <= 0 require.
inline constexpr double kMinBoundGap = 0.05;

//! MAX_cells from its tuned log10: 10^x rounded to the nearest integer.
int max_cells_from_log10(double x);

//! Writes the full variable vector `x` (tuned_variables() order) into a copy of `base`.
//! @throws InputError when x has the wrong size or is not finite.
Params apply_variables(const Params& base, const std::vector<double>& x);

//! The tuned variables' values in `p` (tuned_variables() order); Params{} gives the thesis's.
std::vector<double> variables_of(const Params& p);

//! The constraint values c(x) <= 0 of the two LB < UB pairs: d_t_lb - d_t_ub + gap, d_g_lb - d_g_ub + gap.
std::vector<double> bound_constraints(const std::vector<double>& x);

//! True when x meets both constraints of bound_constraints() (each value <= 0).
bool meets_bound_constraints(const std::vector<double>& x);

//! Link-geom/box pairs whose bounding spheres overlap, averaged over the configurations: how many
//! pairs of one collision check near these configurations get past MuJoCo's bounding-sphere test to
//! the box-box test, the part of a check's cost that the box count alone does not predict.
//! Spheres: MuJoCo's geom_rbound for the links, the half-diagonal for the boxes.
double near_pairs(const Scene& scene, const std::vector<Eigen::VectorXd>& configs,
                  const std::vector<Box>& boxes);

//! Deterministic cost proxy of one single-threaded compute_bounds run [ms]: a fixed cost, a cost per
//! collision check, per check and box (with MuJoCo's full pass every check visits every active box;
//! with the midphase the term carries the volume's generation and injection, linear in the boxes)
//! and per check and near pair (near_pairs at the path's waypoints: the box-box tests). No per-cell
//! term: it is collinear with the box count. Fitted to measured times once per process
//! (fit_time_model); docs/tuning.md, "Noise".
struct TimeModel {
  double ms_fixed = 0;           //!< per run: categorisation, the checker's data for the whole pool
  double ms_per_check = 0;       //!< kinematics and the copy into the pool model
  double ms_per_check_box = 0;   //!< one active box in one collision check (all link geoms)
  double ms_per_check_near = 0;  //!< one near pair in one collision check
  double r2 = 0;                 //!< coefficient of determination of the fit
  double median_rel_error = 0;   //!< median of |predicted - measured| / measured over the fit's samples
  int samples = 0;               //!< measurements the fit used
  //! Predicted time [ms] of a run with `checks` collision checks against `boxes` boxes with `near`
  //! near pairs.
  double predict(long checks, long boxes, double near) const;
};

//! One timing measurement for the fit.
struct TimingSample {
  long checks = 0;  //!< collision checks of the run
  long boxes = 0;   //!< volume boxes
  double near = 0;  //!< near_pairs at the path's waypoints
  double ms = 0;    //!< measured compute_bounds time (median of repeats)
};

//! Least-squares fit of TimeModel to relative errors with non-negative coefficients (the best of the
//! subsets of terms whose unconstrained fit is non-negative). @throws InputError on fewer than 2
//! samples.
TimeModel fit_time_model(const std::vector<TimingSample>& samples);

//! One single-threaded compute_bounds run with its wall and process CPU times [ms].
struct TimedRun {
  BoundsRun run;       //!< the last run (every run gives the same result)
  double wall_ms = 0;  //!< median wall time of the runs
  double cpu_ms = 0;   //!< median process CPU time of the runs
};
//! Runs compute_bounds on one thread `repeats` times; returns the last run and the median times.
TimedRun timed_bounds(TuningCase& c, const Params& params, int repeats);

//! How a parameter set is scored. Per case i, to be maximised (docs/tuning.md, "Objective"):
//!   J_i = 100 CF_i - lambda T_i - mu S_i
//! with CF_i the Confidence Factor (fraction), T_i the time [s] of compute_bounds (proxy or measured)
//! and S_i the mean width shortfall of the bisected intervals: a collapsed interval counts 1, another
//! max(0, 1 - width / min_width). Aggregated over the cases by the mean or the minimum.
struct Objective {
  double lambda = 1.0;      //!< CF percentage points per second of time
  double mu = 10.0;         //!< CF percentage points for a fully narrow path (S = 1)
  double min_width = 0.1;   //!< width [rad] below which a bisected interval falls short
  bool worst_case = false;  //!< aggregate by the minimum over the cases instead of the mean
  //! What T is: the deterministic proxy (TimeModel), or the measured wall or CPU time (medians).
  enum class Time { kProxy, kWall, kCpu } time = Time::kProxy;
};

//! What one evaluation of a parameter set on one case measured.
struct CaseEval {
  double cf = 0;      //!< Confidence Factor (fraction)
  double ci_low = 0;  //!< its 95 % Wilson interval
  double ci_high = 0;
  double wall_ms = 0;     //!< compute_bounds wall time, median of the repeats [ms]
  double cpu_ms = 0;      //!< its process CPU time, median of the repeats [ms]
  double cost_ms = 0;     //!< the TimeModel's prediction [ms]
  long checks = 0;        //!< collision checks
  long boxes = 0;         //!< volume boxes
  double near = 0;        //!< near_pairs at the path's waypoints
  long cells = 0;         //!< height-map cells
  int bisected = 0;       //!< bisected intervals (waypoints x bisected joints)
  int collapsed = 0;      //!< of which the collapse guard widened
  double mean_width = 0;  //!< mean width of the bisected intervals [rad]
  double shortfall = 0;   //!< S_i
  double score = 0;       //!< J_i
};

//! Runs timed_bounds (every run gives the same bounds) and the CF once with `cf` on `cf_threads`
//! threads, then scores the case.
//! @throws InputError on invalid parameters.
CaseEval evaluate_case(TuningCase& c, const Params& params, const CfParams& cf, int repeats, int cf_threads,
                       const TimeModel& model, const Objective& objective);

//! Fills `score` of `e` from its CF, times and shortfall (used by evaluate_case; exposed for tests).
void score_case(CaseEval& e, const Objective& objective);

//! The aggregate of the per-case scores: mean, or minimum when objective.worst_case.
double aggregate_score(const std::vector<CaseEval>& evals, const Objective& objective);

//! Width statistics of bounds: fills bisected, collapsed, mean_width and shortfall of `e` (the
//! bisected joints are those of bound_kinds(scene, params)).
void width_stats(const Scene& scene, const BoundsParams& params, const std::vector<WaypointBounds>& bounds,
                 double min_width, CaseEval& e);

//! The tuned parameter file: `base_json` (may be empty) with the tuned keys set from `p`
//! (height_map.max_cells and the volume keys of tuned_variables()). `leeway bounds --params` reads it.
nlohmann::json tuned_params_json(const nlohmann::json& base_json, const Params& p);

}  // namespace leeway
