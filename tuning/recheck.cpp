#include <algorithm>
#include <iostream>

#include "stages.hpp"

namespace leeway::tune_cli {
namespace {

constexpr double kRecheckGap = 0.02;  // J points between the rechecked evaluations

}  // namespace

void recheck(Problem& pb, const SearchResult& result, FinalEvals& evals) {
  const Options& o = pb.o;
  const Objective& objective = o.objective;
  // Ranking check: K of the best evaluations re-scored with the summary's CF and measured times
  // instead of the proxy.
  std::vector<std::pair<double, std::vector<double>>> top;
  for (const auto& r : result.records)
    if (r.feasible) top.emplace_back(r.objective, r.x);
  std::stable_sort(top.begin(), top.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  // A ladder: the best, then each next one at least kRecheckGap below the previous, so that the
  // order being checked is more than the proxy's microseconds (and no point comes twice: equal
  // parameters score equally).
  std::vector<std::pair<double, std::vector<double>>> ladder;
  for (const auto& t : top)
    if (ladder.size() < static_cast<size_t>(o.recheck) &&
        (ladder.empty() || t.first <= ladder.back().first - kRecheckGap))
      ladder.push_back(t);
  top = ladder;
  json points = json::array();
  std::vector<double> a, b_wall, b_cpu;
  for (size_t i = 0; i < top.size() && interrupt_count() < 2; ++i) {
    std::vector<CaseEval> evs;
    for (size_t k = 0; k < pb.cases.size(); ++k) evs.push_back(evals(k, top[i].second));
    Objective by_wall = objective, by_cpu = objective;
    by_wall.time = Objective::Time::kWall;
    by_cpu.time = Objective::Time::kCpu;
    auto rescore = [&](const Objective& ob) {
      for (auto& e : evs) leeway::score_case(e, ob);
      return leeway::aggregate_score(evs, ob);
    };
    const double jw = rescore(by_wall), jc = rescore(by_cpu);
    a.push_back(top[i].first);
    b_wall.push_back(jw);
    b_cpu.push_back(jc);
    points.push_back({{"search_objective", top[i].first},
                      {"wall_objective", jw},
                      {"cpu_objective", jc},
                      {"x", top[i].second}});
    std::cout << "recheck " << i + 1 << ": search J " << fixed_num(top[i].first, 4)
              << ", summary CF with wall time " << fixed_num(jw, 4) << ", with CPU time " << fixed_num(jc, 4)
              << "\n";
  }
  if (a.size() == top.size()) {
    pb.report["recheck"] = {
        {"points", points}, {"spearman_wall", spearman(a, b_wall)}, {"spearman_cpu", spearman(a, b_cpu)}};
    std::cout << "recheck rank correlation with the search's ranking (Spearman): wall "
              << num(spearman(a, b_wall), 4) << ", CPU " << num(spearman(a, b_cpu), 4) << "\n";
    pb.write_report();
  }
}

}  // namespace leeway::tune_cli
