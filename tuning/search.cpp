#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>

#include "apps/statistics.hpp"
#include "distribute.hpp"
#include "stages.hpp"

namespace leeway::tune_cli {

namespace {

void write_log_header(const Problem& pb, std::ostream& log) {
  log << "eval,stage,feasible,cached";
  for (const auto& v : pb.vars) log << "," << v.name;
  log << ",max_cells,cf_mean,cf_min,wall_ms,cpu_ms,cost_ms,collapsed,bisected,mean_width,shortfall,"
         "objective,"
         "best,elapsed_s";
  for (const auto& l : pb.labels)
    log << ",cf:" << l << ",wall_ms:" << l << ",cpu_ms:" << l << ",cost_ms:" << l << ",collapsed:" << l
        << ",mean_width:" << l << ",score:" << l;
  log << "\n" << std::flush;
}

// One evaluation's cases summed up: means over the cases (and the CF's minimum), intervals summed,
// the mean width weighted by the bisected intervals [rad].
struct CaseMeans {
  double cf_mean = 0, cf_min = 1, wall = 0, cpu = 0, cost = 0, width = 0, shortfall = 0;
  int collapsed = 0, bisected = 0;
};

CaseMeans case_means(const std::vector<CaseEval>& ev) {
  CaseMeans m;
  const double n = static_cast<double>(ev.size());
  for (const auto& e : ev) {
    m.cf_mean += e.cf / n;
    m.cf_min = std::min(m.cf_min, e.cf);
    m.wall += e.wall_ms / n;
    m.cpu += e.cpu_ms / n;
    m.cost += e.cost_ms / n;
    m.collapsed += e.collapsed;
    m.bisected += e.bisected;
    m.width += e.mean_width * e.bisected;
    m.shortfall += e.shortfall / n;
  }
  m.width /= std::max(1, m.bisected);
  return m;
}

// One evaluation's row of the --log CSV (write_log_header's columns); `ev` null when not run.
void write_log_row(std::ostream& log, const leeway::tune::Record& r, int cells,
                   const std::vector<CaseEval>* ev, const CaseMeans& m, size_t cases) {
  log << r.number << "," << r.stage << "," << (r.feasible ? 1 : 0) << "," << (r.cached ? 1 : 0);
  for (double v : r.x) log << "," << num(v, 10);
  log << "," << cells;
  if (ev)
    log << "," << num(100 * m.cf_mean, 10) << "," << num(100 * m.cf_min, 10) << "," << num(m.wall) << ","
        << num(m.cpu) << "," << num(m.cost) << "," << m.collapsed << "," << m.bisected << "," << num(m.width)
        << "," << num(m.shortfall);
  else
    log << ",,,,,,,,,";
  log << "," << num(r.objective, 10) << "," << num(r.best, 10) << "," << num(r.elapsed_s);
  for (size_t k = 0; k < cases; ++k) {
    if (ev) {
      const auto& e = (*ev)[k];
      log << "," << num(100 * e.cf, 10) << "," << num(e.wall_ms) << "," << num(e.cpu_ms) << ","
          << num(e.cost_ms) << "," << e.collapsed << "," << num(e.mean_width) << "," << num(e.score, 10);
    } else {
      log << ",,,,,,,";
    }
  }
  log << "\n" << std::flush;
}

// The search space: the variables' names and bounds, the start, the fixed ones, LB < UB.
leeway::tune::Space space_of(const Problem& pb) {
  leeway::tune::Space space;
  for (size_t i = 0; i < pb.size(); ++i) {
    space.names.push_back(pb.vars[i].name);
    space.lower.push_back(pb.lower(i));
    space.upper.push_back(pb.upper(i));
  }
  space.start = pb.start;
  space.fixed = pb.fixed;
  space.constraints = leeway::bound_constraints;
  space.constraint_count = 2;
  space.canonical = [&pb](const std::vector<double>& x) { return pb.canonical(x); };
  return space;
}

void print_tuned(const Problem& pb, const std::vector<double>& best_x, const Params& best) {
  std::cout << "tuned parameters [thesis]:\n";
  for (size_t i = 0; i < pb.size(); ++i) {
    if (i == kCellsIndex)
      std::cout << "  max_cells     " << best.height_map.max_cells << "  ["
                << leeway::max_cells_from_log10(pb.vars[i].thesis) << "]";
    else
      std::cout << "  " << std::left << std::setw(12) << pb.vars[i].name << std::right << "  "
                << num(best_x[i], 5) << " " << pb.vars[i].unit << "  [" << num(pb.vars[i].thesis) << "]";
    std::cout << (pb.fixed[i] ? "  (fixed)" : "") << "\n";
  }
}

// The time proxy against the measured CPU and wall times of every run of the search.
void check_proxy(Problem& pb, const std::map<std::vector<double>, std::vector<CaseEval>>& details) {
  std::vector<double> cost, wall, cpu, rel;
  for (const auto& [k, evs] : details)
    for (const auto& e : evs) {
      cost.push_back(e.cost_ms);
      wall.push_back(e.wall_ms);
      cpu.push_back(e.cpu_ms);
      if (e.cpu_ms > 0) rel.push_back(std::abs(e.cost_ms - e.cpu_ms) / e.cpu_ms);
    }
  const double rho_cpu = spearman(cost, cpu), rho_wall = spearman(cost, wall),
               err = leeway::detail::median(rel);
  std::cout << "time proxy over the search's " << cost.size() << " runs: Spearman " << num(rho_cpu, 4)
            << " with CPU time, " << num(rho_wall, 4) << " with wall time; median relative error "
            << num(100 * err, 3) << " % (CPU)\n";
  pb.report["proxy_check"] = {{"runs", cost.size()},
                              {"spearman_cpu", rho_cpu},
                              {"spearman_wall", rho_wall},
                              {"median_rel_error_cpu", err}};
}

}  // namespace

std::optional<SearchResult> search(Problem& pb, std::ostream* log, double t0) {
  const Options& o = pb.o;
  const Objective& objective = o.objective;

  SearchResult result;
  auto& details = result.details;  // by canonical variables
  auto& records = result.records;
  auto evaluate = [&](const std::vector<double>& x) -> std::optional<double> {
    if (interrupted()) return std::nullopt;
    // The cases spread over the ranks of an mpirun (distribute.cpp), in case order.
    const std::vector<CaseEval> evals = evaluate_cases(pb, x);
    if (interrupted()) return std::nullopt;
    const double j = leeway::aggregate_score(evals, objective);
    details[pb.canonical(x)] = evals;
    return j;
  };

  if (log) write_log_header(pb, *log);

  auto write_tuned = [&](const std::vector<double>& x) {
    leeway::write_file_atomic(o.out, leeway::tuned_params_json(pb.base_json, pb.params(0, x)).dump(2) + "\n");
  };
  int written = 0;
  double written_objective = 0;
  auto on_record = [&](const leeway::tune::Record& r) {
    records.push_back(r);
    const int cells = leeway::max_cells_from_log10(r.x[kCellsIndex]);
    const std::vector<CaseEval>* ev = nullptr;
    if (r.feasible) {
      const auto it = details.find(pb.canonical(r.x));
      if (it != details.end()) ev = &it->second;
    }
    const CaseMeans mean = ev ? case_means(*ev) : CaseMeans{};
    if (log) write_log_row(*log, r, cells, ev, mean, pb.labels.size());
    // Progress: evaluation number, objective, best so far, elapsed time.
    std::cerr << "[" << r.number << (o.budget_evals > 0 ? "/" + std::to_string(o.budget_evals) : "") << "] "
              << std::left << std::setw(7) << r.stage << std::right << " J " << fixed_num(r.objective, 4)
              << "  best " << fixed_num(r.best, 4);
    if (ev)
      std::cerr << "  CF " << fixed_num(100 * mean.cf_mean, 3) << " %  time "
                << fixed_num(objective.time == Objective::Time::kWall  ? mean.wall
                             : objective.time == Objective::Time::kCpu ? mean.cpu
                                                                       : mean.cost,
                             1)
                << " ms  MAX_cells " << cells << "  collapsed " << mean.collapsed << "/" << mean.bisected;
    else if (!r.feasible)
      std::cerr << "  (violates LB < UB: not run)";
    std::cerr << "  " << fixed_num(r.elapsed_s, 1) << " s" << (r.cached ? "  (cached)" : "") << "\n";
    // The best parameters so far are on disk at every moment: an interrupt (or a kill) keeps them.
    if (r.feasible && (written == 0 || r.objective > written_objective)) {
      write_tuned(r.x);
      written = r.number;
      written_objective = r.objective;
    }
  };

  const leeway::tune::Space space = space_of(pb);
  leeway::tune::Settings settings;
  settings.stages = leeway::tune::parse_stages(o.algorithm, o.global_share);
  settings.budget_evals = o.budget_evals;
  settings.budget_seconds = o.budget_seconds;
  settings.seed = o.seed;
  settings.step = o.step;
  settings.population = o.population;
  // A point that violates LB < UB is not run: it scores below any real evaluation (100 CF - lambda T
  // - mu S >= -lambda T - mu), so that no algorithm mistakes it for progress.
  settings.infeasible_value = -1000 - objective.mu;

  std::cerr << "tuning " << pb.cases.size() << " case(s) with " << o.algorithm << ": J = 100 CF - "
            << num(objective.lambda) << " T[s] - " << num(objective.mu) << " S (min width "
            << num(objective.min_width) << " rad), " << o.aggregate << " over the cases, time " << o.time
            << (pb.pool && pb.pool->size() > 1
                    ? "; cases spread over " + std::to_string(pb.pool->size()) + " MPI ranks"
                    : std::string())
            << "\n";
  const auto outcome = leeway::tune::search(space, settings, evaluate, interrupted, on_record);
  const double search_s = now_s() - t0;
  if (outcome.evaluations == 0) {
    std::cerr << "leeway-tune: interrupted before the first evaluation; nothing written\n";
    return std::nullopt;
  }
  write_tuned(outcome.best_x);
  const Params best = pb.params(0, outcome.best_x);
  std::cout << "stopped: " << outcome.stop << "; " << outcome.evaluations << " evaluations in "
            << fixed_num(search_s, 1) << " s\n";
  std::cout << "best J " << num(outcome.best, 8) << " at evaluation " << outcome.best_number << " (start "
            << num(records.front().objective, 8) << "); wrote " << o.out << "\n";
  print_tuned(pb, outcome.best_x, best);
  check_proxy(pb, details);
  pb.report["search"] = {{"algorithm", o.algorithm},
                         {"global_share", o.global_share},
                         {"seed", o.seed},
                         {"budget_evals", o.budget_evals},
                         {"budget_seconds", o.budget_seconds},
                         {"evaluations", outcome.evaluations},
                         {"stop", outcome.stop},
                         {"seconds", search_s},
                         {"best_evaluation", outcome.best_number},
                         {"best_objective", outcome.best},
                         {"start_objective", records.front().objective},
                         {"best_x", outcome.best_x}};
  pb.report["tuned_params"] = leeway::tuned_params_json(pb.base_json, best);
  pb.write_report();
  result.outcome = outcome;
  result.seconds = search_s;
  return result;
}

}  // namespace leeway::tune_cli
