#include <iostream>
#include <map>

#include "stages.hpp"

namespace leeway::tune_cli {

FinalEvals::FinalEvals(const Problem& pb) : pb_(pb), cf_(pb.o.cf) {
  cf_.samples = pb.o.final_samples;
  cf_.seed = pb.o.final_seed;
}

// By case and canonical variables: the ranking check's first point is the tuned one, evaluated by
// the summary.
CaseEval FinalEvals::operator()(size_t k, const std::vector<double>& x) {
  const auto key = std::make_pair(k, pb_.canonical(x));
  auto it = evals_.find(key);
  if (it == evals_.end())
    it = evals_
             .emplace(key, leeway::evaluate_case(*pb_.cases[k], pb_.params(k, x), cf_, pb_.o.final_repeats,
                                                 pb_.o.threads, pb_.model, pb_.o.objective))
             .first;
  return it->second;
}

void summary(Problem& pb, const SearchResult& result, FinalEvals& evals) {
  const Options& o = pb.o;
  const Objective& objective = o.objective;
  // Before / after: the start parameters at the tuned MAX_cells (and at their own), and the tuned
  // ones, with the summary's CF (fresh seed, more samples) and medians of measured times.
  const leeway::CfParams& cf_final = evals.cf();
  const leeway::tune::Outcome& outcome = result.outcome;
  const Params best = pb.params(0, outcome.best_x);
  const int tuned_cells = best.height_map.max_cells;
  const int start_cells = leeway::max_cells_from_log10(pb.start[kCellsIndex]);
  std::vector<std::pair<std::string, std::vector<double>>> configs;
  std::vector<double> start_at_tuned = pb.start;
  start_at_tuned[kCellsIndex] = outcome.best_x[kCellsIndex];
  configs.emplace_back("start@" + std::to_string(tuned_cells), start_at_tuned);
  if (start_cells != tuned_cells) configs.emplace_back("start@" + std::to_string(start_cells), pb.start);
  configs.emplace_back("tuned", outcome.best_x);
  std::cout
      << "\nbefore / after (CF " << cf_final.windows << " x " << o.final_samples << " samples, seed "
      << o.final_seed << "; times: medians of " << o.final_repeats << " runs, wall (CPU) [proxy] ms):\n"
      << "| case | parameters | MAX_cells | boxes | CF [%] | time [ms] | collapsed | mean width [rad] | J |\n"
      << "|---|---|---:|---:|---:|---|---:|---:|---:|\n";
  json summary = json::array();
  std::map<std::string, std::vector<CaseEval>> per_config;
  for (size_t k = 0; k < pb.cases.size() && interrupt_count() < 2; ++k) {
    json jc = {{"case", pb.labels[k]}, {"configs", json::array()}};
    for (const auto& [name, x] : configs) {
      if (interrupt_count() >= 2) break;
      const Params p = pb.params(k, x);
      const CaseEval e = evals(k, x);
      per_config[name].push_back(e);
      std::cout << "| " << pb.labels[k] << " | " << name << " | " << p.height_map.max_cells << " | "
                << e.boxes << " | " << fixed_num(100 * e.cf, 4) << " | " << fixed_num(e.wall_ms, 1) << " ("
                << fixed_num(e.cpu_ms, 1) << ") [" << fixed_num(e.cost_ms, 1) << "] | " << e.collapsed << "/"
                << e.bisected << " | " << fixed_num(e.mean_width, 3) << " | " << fixed_num(e.score, 3)
                << " |\n"
                << std::flush;
      json je = case_eval_json(e);
      je["name"] = name;
      je["max_cells"] = p.height_map.max_cells;
      jc["configs"].push_back(je);
    }
    summary.push_back(jc);
  }
  pb.report["summary"] = summary;
  pb.report["summary_settings"] = {{"cf_windows", cf_final.windows},
                                   {"cf_samples", o.final_samples},
                                   {"cf_seed", o.final_seed},
                                   {"repeats", o.final_repeats}};
  json totals = json::object();
  for (const auto& [name, evs] : per_config)
    if (evs.size() == pb.cases.size()) {
      totals[name] = leeway::aggregate_score(evs, objective);
      std::cout << "J (" << o.aggregate << " over the cases) " << name << ": "
                << num(totals[name].get<double>(), 8) << "\n";
    }
  pb.report["summary_objective"] = totals;
  pb.write_report();
}

}  // namespace leeway::tune_cli
