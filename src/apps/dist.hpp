#pragma once
// Internal: a pool of processes that runs independent tasks, for `leeway batch` (one scenario per
// task) and leeway-tune (one case of an objective evaluation per task). The serial pool runs them
// in this process; the MPI pool (mpi_runner.cpp, built with LEEWAY_WITH_MPI) spreads them over the
// ranks of an `mpirun`: rank 0 hands out task indices one at a time as ranks become free (and runs
// tasks itself on a second thread), collects the replies and returns them in task order. Tasks and
// replies are text (JSON): the same bytes whichever rank ran them.

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace leeway::dist {

//! What one task returned: its text, or the message of the exception it threw.
struct Reply {
  bool ok = true;
  std::string text;        //!< the handler's result, or the exception's message when !ok
  bool bad_input = false;  //!< the exception was an InputError
};

//! Runs one task; the same function on every rank.
using Handler = std::function<std::string(const std::string& task)>;
//! Called on rank 0 as each task finishes (in the order they finish): task index, its reply, the
//! rank that ran it.
using OnDone = std::function<void(size_t index, const Reply& reply, int rank)>;

//! A pool of ranks (1 for the serial pool).
class Pool {
 public:
  virtual ~Pool() = default;
  //! This process's rank; 0 runs the program's logic and writes every output.
  virtual int rank() const = 0;
  //! Ranks in all.
  virtual int size() const = 0;
  //! Ranks on this machine (the default thread count divides the cores among them).
  virtual int local_size() const = 0;
  //! Rank 0: runs every task over the ranks and returns the replies in task order. A task that
  //! throws gives a Reply with ok = false, never a hang.
  virtual std::vector<Reply> map(const std::vector<std::string>& tasks, const OnDone& on_done) = 0;
  //! Ranks other than 0: run the tasks rank 0 hands out until it finishes (its pool is destroyed).
  virtual void serve() = 0;
};

//! The MPI pool when leeway was built with MPI and this process was started by an MPI launcher
//! (OpenMPI's, PMI or PMIx environment variables); otherwise the serial pool. `handler` runs the
//! tasks. Call it once per process.
//! @throws InputError when an MPI launcher started 2+ ranks of a build without MPI (each would
//! run everything on its own).
std::unique_ptr<Pool> make_pool(Handler handler);

//! Whether this build can spread work over MPI ranks.
bool built_with_mpi();

//! Runs `handler` on `task`, turning an exception into a Reply with ok = false.
Reply run_task(const Handler& handler, const std::string& task);

}  // namespace leeway::dist
