// leeway-tune over MPI ranks: the cases of one objective evaluation are tasks of the
// process pool (src/apps/dist.hpp). Every rank loads the same problem from the same command line; a task
// names the case, the variables and rank 0's time proxy, and its reply is the case's evaluation.
// Numbers travel as JSON, which writes every double so that it reads back exactly: the search sees
// the same values as in a single process.
#include "distribute.hpp"

#include <stdexcept>

namespace leeway::tune_cli {
namespace {

// The reply: case_eval_json's record (problem.hpp), read back field by field.
CaseEval eval_from_json(const json& j) {
  CaseEval e;
  e.cf = j.at("cf");
  e.ci_low = j.at("ci95").at(0);
  e.ci_high = j.at("ci95").at(1);
  e.wall_ms = j.at("wall_ms");
  e.cpu_ms = j.at("cpu_ms");
  e.cost_ms = j.at("cost_ms");
  e.checks = j.at("checks");
  e.boxes = j.at("boxes");
  e.near = j.at("near");
  e.cells = j.at("cells");
  e.bisected = j.at("bisected");
  e.collapsed = j.at("collapsed");
  e.mean_width = j.at("mean_width");
  e.shortfall = j.at("shortfall");
  e.score = j.at("score");
  return e;
}

}  // namespace

dist::Handler case_handler(Problem& pb) {
  return [&pb](const std::string& text) {
    const json task = json::parse(text);
    const size_t k = task.at("case");
    const std::vector<double> x = task.at("x");
    TimeModel model;
    model.ms_fixed = task.at("model").at(0);
    model.ms_per_check = task.at("model").at(1);
    model.ms_per_check_box = task.at("model").at(2);
    model.ms_per_check_near = task.at("model").at(3);
    if (k >= pb.cases.size())
      throw std::runtime_error("case " + std::to_string(k) + " of " + std::to_string(pb.cases.size()));
    const Options& o = pb.o;
    return case_eval_json(leeway::evaluate_case(*pb.cases[k], pb.params(k, x), o.cf, o.repeats, o.threads,
                                                model, o.objective))
        .dump();
  };
}

std::vector<CaseEval> evaluate_cases(Problem& pb, const std::vector<double>& x) {
  const TimeModel& m = pb.model;
  std::vector<std::string> tasks;
  for (size_t k = 0; k < pb.cases.size(); ++k)
    tasks.push_back(json{{"case", k},
                         {"x", x},
                         {"model", {m.ms_fixed, m.ms_per_check, m.ms_per_check_box, m.ms_per_check_near}}}
                        .dump());
  const auto replies = pb.pool->map(tasks, {});
  std::vector<CaseEval> evals;
  for (size_t k = 0; k < replies.size(); ++k) {
    if (!replies[k].ok && replies[k].bad_input) throw InputError(replies[k].text);
    if (!replies[k].ok) throw std::runtime_error("case " + pb.labels[k] + ": " + replies[k].text);
    evals.push_back(eval_from_json(json::parse(replies[k].text)));
  }
  return evals;
}

}  // namespace leeway::tune_cli
