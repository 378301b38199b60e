// The MPI pool of dist.hpp (compiled only when CMake found MPI and LEEWAY_WITH_MPI is on). Rank 0
// hands out one task index at a time to each free rank and runs tasks itself on a second thread;
// only rank 0's main thread calls MPI (MPI_THREAD_FUNNELED). Idle ranks poll with short sleeps
// rather than in a blocking receive, which OpenMPI busy-waits: a waiting rank costs no core.
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <future>
#include <set>
#include <stdexcept>
#include <thread>

#include "dist.hpp"

namespace leeway::dist {
namespace {

constexpr int kTagTask = 1;   // rank 0 -> worker: 8-byte index, then the task's text
constexpr int kTagReply = 2;  // worker -> rank 0: 8-byte index, 1 byte (1 ok, 0 failed, 2 bad input), text
constexpr int kTagStop = 3;   // rank 0 -> worker: no more tasks

// Sleeps between polls: from 20 us, doubling up to 2 ms, back to 20 us when something happened.
class Backoff {
 public:
  void reset() { us_ = 20; }
  void wait() {
    std::this_thread::sleep_for(std::chrono::microseconds(us_));
    us_ = std::min(us_ * 2, 2000);
  }

 private:
  int us_ = 20;
};

std::string pack(uint64_t index, const std::string& text, int ok = -1) {
  std::string m(sizeof index, '\0');
  std::memcpy(m.data(), &index, sizeof index);
  if (ok >= 0) m += static_cast<char>(ok);
  return m + text;
}

// Receives the message `status` announced.
std::string receive(const MPI_Status& probed) {
  int count = 0;
  MPI_Get_count(&probed, MPI_BYTE, &count);
  std::string buf(static_cast<size_t>(count), '\0');
  MPI_Recv(buf.data(), count, MPI_BYTE, probed.MPI_SOURCE, probed.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return buf;
}

void send(const std::string& m, int to, int tag) {
  MPI_Send(m.data(), static_cast<int>(m.size()), MPI_BYTE, to, tag, MPI_COMM_WORLD);
}

uint64_t index_of(const std::string& m) {
  if (m.size() < sizeof(uint64_t))
    throw std::runtime_error("MPI pool: a message of " + std::to_string(m.size()) + " bytes");
  uint64_t i = 0;
  std::memcpy(&i, m.data(), sizeof i);
  return i;
}

class MpiPool : public Pool {
 public:
  explicit MpiPool(Handler handler) : handler_(std::move(handler)) {
    // OpenMPI's shared-memory transport copies large messages between processes with
    // process_vm_readv, which containers often forbid (each such message then fails). Replies are
    // kilobytes: the plain copy costs nothing. A value the user set is kept.
    ::setenv("OMPI_MCA_btl_vader_single_copy_mechanism", "none", 0);
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    if (provided < MPI_THREAD_FUNNELED) {
      MPI_Finalize();
      throw std::runtime_error("the MPI library does not support MPI_THREAD_FUNNELED");
    }
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    MPI_Comm local;
    MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &local);
    MPI_Comm_size(local, &local_size_);
    MPI_Comm_free(&local);
  }

  ~MpiPool() override {
    if (rank_ == 0) {
      // Replies still under way (map left by an exception) are taken before the workers stop.
      Backoff backoff;
      while (!busy_.empty()) {
        int flag = 0;
        MPI_Status st;
        MPI_Iprobe(MPI_ANY_SOURCE, kTagReply, MPI_COMM_WORLD, &flag, &st);
        if (!flag) {
          backoff.wait();
          continue;
        }
        receive(st);
        busy_.erase(st.MPI_SOURCE);
      }
      for (int r = 1; r < size_; ++r) send("", r, kTagStop);
    }
    MPI_Finalize();
  }

  int rank() const override { return rank_; }
  int size() const override { return size_; }
  int local_size() const override { return local_size_; }

  std::vector<Reply> map(const std::vector<std::string>& tasks, const OnDone& on_done) override {
    std::vector<Reply> replies(tasks.size());
    size_t next = 0, done = 0;
    const auto hand_out = [&](int to) {
      send(pack(next, tasks[next]), to, kTagTask);
      busy_.insert(to);
      ++next;
    };
    for (int r = 1; r < size_ && next < tasks.size(); ++r) hand_out(r);
    // Rank 0's own share, on a second thread (this one alone calls MPI).
    std::future<Reply> local;
    size_t local_index = 0;
    const auto start_local = [&] {
      if (next >= tasks.size()) return;
      local_index = next++;
      local = std::async(std::launch::async,
                         [this, &tasks, i = local_index] { return run_task(handler_, tasks[i]); });
    };
    start_local();
    Backoff backoff;
    while (done < tasks.size()) {
      bool progressed = false;
      int flag = 0;
      MPI_Status st;
      MPI_Iprobe(MPI_ANY_SOURCE, kTagReply, MPI_COMM_WORLD, &flag, &st);
      if (flag) {
        const std::string m = receive(st);
        busy_.erase(st.MPI_SOURCE);
        const uint64_t i = index_of(m);
        if (i >= tasks.size() || m.size() < sizeof i + 1)
          throw std::runtime_error("MPI pool: a malformed reply");
        replies[i] = {m[sizeof i] == 1, m.substr(sizeof i + 1), m[sizeof i] == 2};
        ++done;
        if (on_done) on_done(i, replies[i], st.MPI_SOURCE);
        if (next < tasks.size()) hand_out(st.MPI_SOURCE);
        progressed = true;
      }
      if (local.valid() && local.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
        replies[local_index] = local.get();
        ++done;
        if (on_done) on_done(local_index, replies[local_index], 0);
        start_local();
        progressed = true;
      }
      if (progressed)
        backoff.reset();
      else
        backoff.wait();
    }
    return replies;
  }

  void serve() override {
    Backoff backoff;
    for (;;) {
      int flag = 0;
      MPI_Status st;
      MPI_Iprobe(0, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &st);
      if (!flag) {
        backoff.wait();
        continue;
      }
      backoff.reset();
      const std::string m = receive(st);
      if (st.MPI_TAG == kTagStop) return;
      const uint64_t i = index_of(m);
      const Reply r = run_task(handler_, m.substr(sizeof i));
      send(pack(i, r.text, r.ok ? 1 : r.bad_input ? 2 : 0), 0, kTagReply);
    }
  }

 private:
  Handler handler_;
  int rank_ = 0, size_ = 1, local_size_ = 1;
  std::set<int> busy_;  // workers with a task out (rank 0)
};

// Whether an MPI launcher started this process: OpenMPI's mpirun, PMI (MPICH, Slurm) or PMIx.
bool launched_by_mpi() {
  for (const char* var : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMI_RANK", "PMIX_RANK"})
    if (std::getenv(var)) return true;
  return false;
}

}  // namespace

std::unique_ptr<Pool> make_mpi_pool(const Handler& handler) {
  if (!launched_by_mpi()) return nullptr;
  return std::make_unique<MpiPool>(handler);
}

}  // namespace leeway::dist
