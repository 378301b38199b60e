#pragma once
// The NLopt loop of leeway-tune: stages of derivative-free algorithms over the free tuned variables,
// the LB < UB constraints given to NLopt, evaluation and time budgets, forced stop on request.
// docs/tuning.md, "Algorithm".

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace leeway::tune {

//! One stage of the search: an NLopt algorithm, wrapped in NLopt's augmented Lagrangian (AUGLAG)
//! when it cannot take the inequality constraints itself.
struct Stage {
  std::string name;     //!< as given: cobyla, bobyqa, neldermead, sbplx, isres, direct, crs2, esch
  int algorithm = 0;    //!< nlopt::algorithm run on the objective (AUGLAG when wrapped)
  int subsidiary = -1;  //!< the wrapped algorithm under AUGLAG, or -1
  bool global = false;  //!< a global algorithm (ignores the start point or samples the box)
  double share = 1.0;   //!< share of the budgets
};

//! Parses "isres+cobyla" (stages in order) into stages; global stages get `global_share` of the
//! budgets between them, local ones the rest. @throws leeway::InputError naming an unknown name.
std::vector<Stage> parse_stages(const std::string& text, double global_share);

//! The names parse_stages() accepts, comma-separated.
std::string stage_names();

//! The search space: every tuned variable with its bounds; `fixed` ones keep `start`.
struct Space {
  std::vector<std::string> names;
  std::vector<double> lower, upper, start;
  std::vector<bool> fixed;
  //! Constraints c(x_full) <= 0, each with the variables it involves.
  std::function<std::vector<double>(const std::vector<double>&)> constraints;
  int constraint_count = 0;
  //! Maps variables to the values that decide the result (e.g. MAX_cells rounded), so that points
  //! differing only below the rounding are evaluated once. Identity when empty.
  std::function<std::vector<double>(const std::vector<double>&)> canonical;
};

//! One call of the objective.
struct Record {
  int number = 0;         //!< 1-based evaluation number
  std::string stage;      //!< stage name, or "start"
  std::vector<double> x;  //!< all variables
  bool feasible = true;   //!< all constraints held (otherwise not run, objective = infeasible_value)
  bool cached = false;    //!< the same parameters were evaluated before (same result, not rerun)
  double objective = 0;   //!< J (maximised)
  double best = 0;        //!< best feasible J so far, this one included
  double elapsed_s = 0;   //!< since the search started
};

//! Budgets and settings of the search.
struct Settings {
  std::vector<Stage> stages;
  long budget_evals = 0;        //!< objective calls in all (0: no limit)
  double budget_seconds = 0;    //!< wall time of the search [s] (0: no limit)
  unsigned long seed = 1;       //!< NLopt's random seed (ISRES, CRS2, ESCH)
  double step = 0.1;            //!< local algorithms' initial step, as a fraction of each variable's range
  int population = 0;           //!< population of ISRES, CRS2, ESCH (0: 2 (free variables + 1))
  double xtol_rel = 1e-4;       //!< local stages stop when the step is below this (relative)
  double infeasible_value = 0;  //!< J given to points that violate a constraint (they are not run)
  //! A constraint holds when c(x) <= this (NLopt's tolerance too): an algorithm that ends on the
  //! boundary lands there up to rounding.
  double constraint_tol = 1e-9;
};

//! What the search found.
struct Outcome {
  std::vector<double> best_x;  //!< all variables at the best feasible evaluation (the start if none)
  double best = 0;             //!< its J
  int best_number = 0;         //!< its evaluation number
  int evaluations = 0;
  std::string stop;  //!< why it stopped
};

//! Evaluates all variables; returns J, or nothing when interrupted before it finished.
using Evaluate = std::function<std::optional<double>(const std::vector<double>&)>;

//! Runs the stages. Evaluation 1 is always the start point (so the search can only improve on it),
//! and each later stage starts from the best point so far. When every stage has converged and budget
//! is left, the stages run again (a new cycle, its stage names suffixed "#2", "#3"...) on the rest
//! of the budgets with the local steps halved. Stops at the budgets, when a cycle evaluates nothing
//! new or the step falls below 0.1 % of the ranges, or when `interrupted()` turns true (checked
//! before each evaluation; the evaluation function checks it inside). Calls `on_record` after every
//! objective call.
//! @throws the evaluation function's exceptions (rethrown after NLopt stopped).
Outcome search(const Space& space, const Settings& settings, const Evaluate& evaluate,
               const std::function<bool()>& interrupted, const std::function<void(const Record&)>& on_record);

}  // namespace leeway::tune
