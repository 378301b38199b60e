#include "tuner.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <map>
#include <nlopt.hpp>

#include "leeway/core/error.hpp"

namespace leeway::tune {
namespace {

struct AlgorithmName {
  const char* name;
  nlopt::algorithm algorithm;
  bool global;
  bool takes_constraints;  // inequality constraints natively; otherwise wrapped in AUGLAG
};

const AlgorithmName kAlgorithms[] = {
    {"cobyla", nlopt::LN_COBYLA, false, true},
    {"bobyqa", nlopt::LN_BOBYQA, false, false},
    {"neldermead", nlopt::LN_NELDERMEAD, false, false},
    {"sbplx", nlopt::LN_SBPLX, false, false},
    {"isres", nlopt::GN_ISRES, true, true},
    {"direct", nlopt::GN_ORIG_DIRECT_L, true, true},
    {"crs2", nlopt::GN_CRS2_LM, true, false},
    {"esch", nlopt::GN_ESCH, true, false},
};

using Clock = std::chrono::steady_clock;

// The search's state, shared with NLopt's callbacks.
struct Run {
  Run(const Space& sp, const Settings& se, const Evaluate& ev, const std::function<bool()>& in,
      const std::function<void(const Record&)>& on)
      : space(sp), settings(se), evaluate(ev), interrupted(in), on_record(on) {}
  const Space& space;
  const Settings& settings;
  const Evaluate& evaluate;
  const std::function<bool()>& interrupted;
  const std::function<void(const Record&)>& on_record;
  std::vector<size_t> free;  // indices of the free variables
  Clock::time_point t0 = Clock::now();
  int count = 0;
  Outcome out;
  bool have_best = false;
  std::map<std::vector<double>, double> cache;
  // The current stage.
  std::string stage;
  nlopt::opt* opt = nullptr;
  long stage_end_evals = 0;      // the stage ends when count reaches this (0: no limit)
  double stage_end_seconds = 0;  // or when elapsed reaches this (0: no limit)
  bool halt = false;             // stop everything
  bool stage_over = false;
  std::exception_ptr error;
  double last = 0;

  double elapsed() const { return std::chrono::duration<double>(Clock::now() - t0).count(); }

  std::vector<double> full(const std::vector<double>& xf) const {
    std::vector<double> x = space.start;  // fixed variables keep their start value
    for (size_t k = 0; k < free.size(); ++k) x[free[k]] = xf[k];
    return x;
  }

  // One objective call. Returns false when interrupted during the evaluation.
  bool evaluate_point(const std::vector<double>& x, double& value) {
    Record r;
    r.x = x;
    r.stage = stage;
    bool feasible = true;
    if (space.constraints)
      for (double c : space.constraints(x)) feasible = feasible && c <= settings.constraint_tol;
    const std::vector<double> key = space.canonical ? space.canonical(x) : x;
    if (!feasible) {
      value = settings.infeasible_value;
    } else if (auto it = cache.find(key); it != cache.end()) {
      value = it->second;
      r.cached = true;
    } else {
      const auto v = evaluate(x);
      if (!v) return false;
      value = *v;
      cache.emplace(key, value);
    }
    r.number = ++count;
    r.feasible = feasible;
    r.objective = value;
    if (feasible && (!have_best || value > out.best)) {
      have_best = true;
      out.best = value;
      out.best_x = x;
      out.best_number = r.number;
    }
    r.best = have_best ? out.best : value;
    r.elapsed_s = elapsed();
    on_record(r);
    return true;
  }

  // Checks the budgets and the interrupt before an evaluation; false when none is allowed.
  bool may_evaluate() {
    if (halt || stage_over) return false;
    if (interrupted()) {
      out.stop = "interrupted (SIGINT)";
      halt = true;
    } else if (settings.budget_evals > 0 && count >= settings.budget_evals) {
      out.stop = "evaluation budget (" + std::to_string(settings.budget_evals) + ") used";
      halt = true;
    } else if (settings.budget_seconds > 0 && elapsed() >= settings.budget_seconds) {
      out.stop = "time budget used";
      halt = true;
    } else if ((stage_end_evals > 0 && count >= stage_end_evals) ||
               (stage_end_seconds > 0 && elapsed() >= stage_end_seconds)) {
      stage_over = true;
    }
    return !halt && !stage_over;
  }

  static double objective(const std::vector<double>& xf, std::vector<double>& /*grad*/, void* data) {
    Run& run = *static_cast<Run*>(data);
    try {
      if (!run.may_evaluate()) {
        run.opt->force_stop();
        return run.last;
      }
      double v = 0;
      if (!run.evaluate_point(run.full(xf), v)) {
        run.out.stop = "interrupted (SIGINT)";
        run.halt = true;
        run.opt->force_stop();
        return run.last;
      }
      run.last = v;
      return v;
    } catch (...) {
      run.error = std::current_exception();
      run.halt = true;
      run.opt->force_stop();
      return run.last;
    }
  }
};

// Constraint i of the space, as NLopt calls it.
struct ConstraintData {
  Run* run;
  size_t index;
};

double constraint(const std::vector<double>& xf, std::vector<double>& /*grad*/, void* data) {
  const auto& d = *static_cast<ConstraintData*>(data);
  return d.run->space.constraints(d.run->full(xf))[d.index];
}

}  // namespace

std::string stage_names() {
  std::string s;
  for (const auto& a : kAlgorithms) s += (s.empty() ? "" : ", ") + std::string(a.name);
  return s;
}

std::vector<Stage> parse_stages(const std::string& text, double global_share) {
  if (!(global_share > 0 && global_share < 1))
    throw InputError("--global-share " + std::to_string(global_share) + " must be between 0 and 1");
  std::vector<Stage> stages;
  std::string rest = text + "+";
  for (size_t pos = rest.find('+'); pos != std::string::npos; pos = rest.find('+')) {
    const std::string name = rest.substr(0, pos);
    rest = rest.substr(pos + 1);
    const AlgorithmName* found = nullptr;
    for (const auto& a : kAlgorithms)
      if (name == a.name) found = &a;
    if (!found)
      throw InputError("--algorithm '" + text + "': unknown stage '" + name + "'; stages: " + stage_names() +
                       ", joined with '+' (e.g. isres+cobyla)");
    Stage s;
    s.name = found->name;
    s.global = found->global;
    if (found->takes_constraints) {
      s.algorithm = static_cast<int>(found->algorithm);
    } else {
      s.algorithm = static_cast<int>(nlopt::AUGLAG);
      s.subsidiary = static_cast<int>(found->algorithm);
    }
    stages.push_back(s);
  }
  const auto globals = std::count_if(stages.begin(), stages.end(), [](const Stage& s) { return s.global; });
  const auto locals = static_cast<long>(stages.size()) - globals;
  for (auto& s : stages) {
    if (globals == 0 || locals == 0)
      s.share = 1.0 / static_cast<double>(stages.size());
    else
      s.share = s.global ? global_share / static_cast<double>(globals)
                         : (1 - global_share) / static_cast<double>(locals);
  }
  return stages;
}

Outcome search(const Space& space, const Settings& settings, const Evaluate& evaluate,
               const std::function<bool()>& interrupted,
               const std::function<void(const Record&)>& on_record) {
  const size_t n = space.start.size();
  LEEWAY_DEMAND(space.lower.size() == n && space.upper.size() == n && space.fixed.size() == n &&
                space.names.size() == n);
  if (settings.budget_evals <= 0 && settings.budget_seconds <= 0)
    throw InputError("give a budget: --budget-evals N or --budget-seconds S");
  Run run(space, settings, evaluate, interrupted, on_record);
  for (size_t i = 0; i < n; ++i)
    if (!space.fixed[i]) run.free.push_back(i);

  // Evaluation 1: the start point.
  run.stage = "start";
  if (!run.may_evaluate()) return run.out;
  {
    double v = 0;
    if (!run.evaluate_point(space.start, v)) {
      run.out.stop = "interrupted (SIGINT)";
      run.out.evaluations = run.count;
      if (run.out.best_x.empty()) run.out.best_x = space.start;
      return run.out;
    }
    run.last = v;
  }
  if (run.free.empty()) {
    run.out.stop = "no free variable";
    run.out.evaluations = run.count;
    return run.out;
  }

  const unsigned nf = static_cast<unsigned>(run.free.size());
  std::vector<double> lo(nf), hi(nf);
  for (unsigned k = 0; k < nf; ++k) {
    lo[k] = space.lower[run.free[k]];
    hi[k] = space.upper[run.free[k]];
  }
  std::vector<ConstraintData> cdata;
  for (int c = 0; c < space.constraint_count; ++c) cdata.push_back({&run, static_cast<size_t>(c)});
  const unsigned population =
      settings.population > 0 ? static_cast<unsigned>(settings.population) : 2 * (nf + 1);

  // Cycles of the stages: when every stage has converged with budget left, the stages run again
  // from the best point, on the rest of the budgets, with the local steps halved.
  nlopt::srand(settings.seed);
  double step_fraction = settings.step;
  for (int cycle = 1; !run.halt; ++cycle) {
    const int cycle_start = run.count;
    const double cycle_t0 = run.elapsed();
    const double evals_left = static_cast<double>(settings.budget_evals - run.count);
    const double seconds_left = settings.budget_seconds - cycle_t0;
    std::vector<double> step(nf);
    for (unsigned k = 0; k < nf; ++k) step[k] = step_fraction * (hi[k] - lo[k]);
    double share_sum = 0;
    for (size_t s = 0; s < settings.stages.size() && !run.halt; ++s) {
      const Stage& stage = settings.stages[s];
      share_sum += stage.share;
      // DIRECT ignores the start point and is deterministic: a second cycle would repeat it.
      if (cycle > 1 && stage.name == "direct") continue;
      const bool last = s + 1 == settings.stages.size();
      run.stage = cycle == 1 ? stage.name : stage.name + "#" + std::to_string(cycle);
      run.stage_over = false;
      run.stage_end_evals =
          settings.budget_evals > 0 && !last ? cycle_start + std::lround(share_sum * evals_left) : 0;
      run.stage_end_seconds = settings.budget_seconds > 0 && !last ? cycle_t0 + share_sum * seconds_left : 0;

      nlopt::opt opt(static_cast<nlopt::algorithm>(stage.algorithm), nf);
      run.opt = &opt;
      opt.set_lower_bounds(lo);
      opt.set_upper_bounds(hi);
      opt.set_max_objective(Run::objective, &run);
      for (auto& d : cdata) opt.add_inequality_constraint(constraint, &d, settings.constraint_tol);
      opt.set_xtol_rel(settings.xtol_rel);
      if (!stage.global) opt.set_initial_step(step);
      if (stage.global && stage.subsidiary < 0) opt.set_population(population);
      if (stage.subsidiary >= 0) {
        // AUGLAG: the constraints go into its penalty; the wrapped algorithm sees only the bounds.
        nlopt::opt sub(static_cast<nlopt::algorithm>(stage.subsidiary), nf);
        sub.set_lower_bounds(lo);
        sub.set_upper_bounds(hi);
        sub.set_xtol_rel(settings.xtol_rel);
        if (stage.global)
          sub.set_population(population);
        else
          sub.set_initial_step(step);
        opt.set_local_optimizer(sub);
      }
      // Each stage starts from the best point so far.
      std::vector<double> xf(nf);
      const std::vector<double>& from = run.out.best_x.empty() ? space.start : run.out.best_x;
      for (unsigned k = 0; k < nf; ++k) xf[k] = std::clamp(from[run.free[k]], lo[k], hi[k]);
      double f = 0;
      try {
        opt.optimize(xf, f);
      } catch (const nlopt::forced_stop&) {
      } catch (const nlopt::roundoff_limited&) {
      }
      run.opt = nullptr;
      if (run.error) std::rethrow_exception(run.error);
    }
    if (run.halt) break;
    step_fraction /= 2;
    if (run.count == cycle_start || step_fraction < 1e-3) {
      run.out.stop = "converged";
      break;
    }
  }
  run.out.evaluations = run.count;
  return run.out;
}

}  // namespace leeway::tune
