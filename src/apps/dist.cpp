#include "dist.hpp"

#include <cstdlib>
#include <exception>
#include <string>

#include "leeway/core/error.hpp"

namespace leeway::dist {

#ifdef LEEWAY_WITH_MPI
// mpi_runner.cpp: the MPI pool, or nullptr when not started by an MPI launcher with 2+ ranks.
std::unique_ptr<Pool> make_mpi_pool(const Handler& handler);
#endif

namespace {

// Every task in this process, in order.
class SerialPool : public Pool {
 public:
  explicit SerialPool(Handler handler) : handler_(std::move(handler)) {}
  int rank() const override { return 0; }
  int size() const override { return 1; }
  int local_size() const override { return 1; }
  std::vector<Reply> map(const std::vector<std::string>& tasks, const OnDone& on_done) override {
    std::vector<Reply> replies;
    for (size_t i = 0; i < tasks.size(); ++i) {
      replies.push_back(run_task(handler_, tasks[i]));
      if (on_done) on_done(i, replies.back(), 0);
    }
    return replies;
  }
  void serve() override {}

 private:
  Handler handler_;
};

}  // namespace

Reply run_task(const Handler& handler, const std::string& task) {
  try {
    return {true, handler(task), false};
  } catch (const InputError& e) {
    return {false, e.what(), true};
  } catch (const std::exception& e) {
    return {false, e.what(), false};
  } catch (...) {
    return {false, "unknown exception", false};
  }
}

bool built_with_mpi() {
#ifdef LEEWAY_WITH_MPI
  return true;
#else
  return false;
#endif
}

std::unique_ptr<Pool> make_pool(Handler handler) {
#ifdef LEEWAY_WITH_MPI
  if (auto pool = make_mpi_pool(handler)) return pool;
#else
  for (const char* var : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
    if (const char* n = std::getenv(var); n && std::atoi(n) > 1)
      throw InputError(std::string("this program was started as one of ") + n +
                       " MPI ranks but built without MPI (LEEWAY_WITH_MPI off): each rank would run "
                       "everything; run it without mpirun, or build it with MPI (docs/batch.md)");
#endif
  return std::make_unique<SerialPool>(std::move(handler));
}

}  // namespace leeway::dist
