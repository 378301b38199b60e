#pragma once
// Internal to leeway-tune: the cases of an objective evaluation as tasks of the process pool
// (src/apps/dist.hpp), on one process or over MPI ranks (docs/batch.md, "leeway-tune over MPI").

#include <vector>

#include "apps/dist.hpp"
#include "problem.hpp"

namespace leeway::tune_cli {

//! The task handler every rank runs: evaluates one case of `pb` at the task's variables.
dist::Handler case_handler(Problem& pb);

//! Evaluates every case at `x` through pb.pool, in case order.
//! @throws std::runtime_error when a case failed on its rank.
std::vector<CaseEval> evaluate_cases(Problem& pb, const std::vector<double>& x);

}  // namespace leeway::tune_cli
