#pragma once
// Internal to leeway-tune: its stages, in the order they run: calibrate (the time proxy), then
// either noise_study or search, summary and recheck. docs/tuning.md.

#include <map>
#include <optional>
#include <ostream>
#include <vector>

#include "problem.hpp"
#include "tuner.hpp"

namespace leeway::tune_cli {

//! Fits the time proxy (pb.model) and records it in the report. Returns false when interrupted.
bool calibrate(Problem& pb);

//! --noise-study K: evaluations of K points repeated into `log`; returns the exit code.
int noise_study(Problem& pb, std::ostream& log);

//! What the search found and every evaluation of it.
struct SearchResult {
  tune::Outcome outcome;
  std::vector<tune::Record> records;
  std::map<std::vector<double>, std::vector<CaseEval>> details;  //!< by canonical variables
  double seconds = 0;                                            //!< since `t0` of search()
};

//! The search: evaluations logged to `log` (when given), the best parameters kept on disk at every
//! moment, then the result printed (and the time proxy checked against measured times) and written
//! to the report. Nothing when interrupted before the first evaluation (said on standard error).
std::optional<SearchResult> search(Problem& pb, std::ostream* log, double t0);

//! The summary's evaluations of (case, variables): CF with the summary's samples and seed, medians
//! of measured times; each runs once, the summary and the ranking check share them.
class FinalEvals {
 public:
  explicit FinalEvals(const Problem& pb);
  //! The CF settings of the summary.
  const CfParams& cf() const { return cf_; }
  //! Case k at variables x.
  CaseEval operator()(size_t k, const std::vector<double>& x);

 private:
  const Problem& pb_;
  CfParams cf_;
  std::map<std::pair<size_t, std::vector<double>>, CaseEval> evals_;
};

//! Before / after: the start parameters at the tuned MAX_cells (and at their own) and the tuned
//! ones, printed as a table and written to the report.
void summary(Problem& pb, const SearchResult& result, FinalEvals& evals);

//! --recheck K: K of the best evaluations re-scored with the summary's CF and measured times.
void recheck(Problem& pb, const SearchResult& result, FinalEvals& evals);

}  // namespace leeway::tune_cli
