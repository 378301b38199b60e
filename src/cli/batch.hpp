#pragma once
// `leeway batch`: a suite of scenarios with expectations, on one process or over MPI ranks
// (docs/batch.md).

#include <CLI/CLI.hpp>
#include <string>

#include "cli/common.hpp"

namespace leeway::cli {

//! The command line of `leeway batch`.
struct BatchArgs {
  std::string suite;  //!< the suite file (JSON)
  std::string junit;  //!< JUnit XML report to write; empty: none
  std::string out;    //!< results JSON to write; empty: none
  int threads = 0;    //!< worker threads per scenario; 0: this machine's cores divided among its ranks,
                      //!< at most the cores this process is bound to
};

//! Adds the `batch` subcommand, parsing into `args`; returns it.
CLI::App* add_batch(CLI::App& app, BatchArgs& args);

//! Runs `leeway batch`: kExitOk when every expectation is met, kExitFindings when one failed or a
//! scenario could not run. Under mpirun, ranks other than 0 run scenarios and print nothing.
//! @throws InputError on a bad suite or output file, before any scenario runs.
int run_batch(const BatchArgs& args);

}  // namespace leeway::cli
