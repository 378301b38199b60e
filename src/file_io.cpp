#include "leeway/file_io.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <mutex>

#include "leeway/error.hpp"

namespace leeway {
namespace {

namespace fs = std::filesystem;

// What a non-regular file is, for the messages.
const char* kind_of(const fs::file_status& s) {
  switch (s.type()) {
    case fs::file_type::directory:
      return "a folder";
    case fs::file_type::fifo:
      return "a FIFO (named pipe)";
    case fs::file_type::character:
    case fs::file_type::block:
      return "a device";
    case fs::file_type::socket:
      return "a socket";
    default:
      return "not a regular file";
  }
}

// The temporary files being written: a fixed table a signal handler can read without allocating.
// A slot is claimed by compare-exchange on `used`, its path written, then `ready` set; the handler
// only unlinks ready slots.
constexpr int kTempSlots = 32;
constexpr size_t kTempPathMax = 4096;
struct TempSlot {
  std::atomic<bool> used{false};
  std::atomic<bool> ready{false};
  char path[kTempPathMax];
};
std::array<TempSlot, kTempSlots> g_temp_slots;

void remove_temp_files_and_reraise(int sig) {
  for (auto& slot : g_temp_slots)
    if (slot.ready.load()) ::unlink(slot.path);  // async-signal-safe
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

// Registers `path` while it exists; an overflowing table only loses the clean-up, not the write.
class TempRegistration {
 public:
  explicit TempRegistration(const std::string& path) {
    if (path.size() >= kTempPathMax) return;
    for (int i = 0; i < kTempSlots; ++i) {
      bool expected = false;
      if (g_temp_slots[i].used.compare_exchange_strong(expected, true)) {
        std::memcpy(g_temp_slots[i].path, path.c_str(), path.size() + 1);
        g_temp_slots[i].ready.store(true);
        slot_ = i;
        return;
      }
    }
  }
  ~TempRegistration() {
    if (slot_ < 0) return;
    g_temp_slots[slot_].ready.store(false);
    g_temp_slots[slot_].used.store(false);
  }
  TempRegistration(const TempRegistration&) = delete;
  TempRegistration& operator=(const TempRegistration&) = delete;

 private:
  int slot_ = -1;
};

}  // namespace

void require_regular_input(const std::string& path, const std::string& what) {
  std::error_code ec;
  const fs::file_status s = fs::status(path, ec);  // follows links; never opens the file
  if (path.empty()) throw InputError("the " + what + " name is empty");
  if (ec || !fs::exists(s)) throw InputError(path + ": cannot open the " + what + " (missing or unreadable)");
  if (!fs::is_regular_file(s))
    throw InputError(path + ": the " + what + " is " + kind_of(s) + ", not a regular file");
}

void require_regular_output(const std::string& path, const std::vector<std::string>& inputs) {
  if (path.empty()) throw InputError("the output file name is empty");
  std::error_code ec;
  const fs::file_status s = fs::status(path, ec);
  if (!fs::exists(s)) return;
  if (!fs::is_regular_file(s))
    throw InputError(path + ": the output file is " + kind_of(s) +
                     ", not a regular file; leeway only writes regular files");
  for (const auto& input : inputs) {
    if (input.empty()) continue;
    if (fs::equivalent(path, input, ec) && !ec)
      throw InputError(path + ": the output file is the input file " + input + "; it would be overwritten");
  }
}

void write_file_atomic(const std::string& path, const std::string& text) {
  require_regular_output(path);
  const fs::path target(path);
  const fs::path tmp =
      target.parent_path() / ("." + target.filename().string() + ".tmp" + std::to_string(::getpid()));
  TempRegistration registered(tmp.string());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) throw InputError(path + ": cannot write the output file (folder missing or not writable)");
  auto fail = [&](const std::string& what) {
    const std::string reason = std::strerror(errno);
    ::close(fd);
    ::unlink(tmp.c_str());
    throw InputError(path + ": " + what + " (" + reason + ")");
  };
  for (size_t done = 0; done < text.size();) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail("writing the output file failed");
    done += static_cast<size_t>(n);
  }
  // On disk before the rename, so that a crash leaves the old file or the new one, never an empty one.
  if (::fsync(fd) != 0) fail("writing the output file to disk failed");
  if (::close(fd) != 0) {
    const std::string reason = std::strerror(errno);
    ::unlink(tmp.c_str());
    throw InputError(path + ": writing the output file failed (" + reason + ")");
  }
  std::error_code ec;
  fs::rename(tmp, target, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw InputError(path + ": cannot move the output file into place");
  }
}

void install_temp_file_cleanup() {
  static std::once_flag once;
  std::call_once(once, [] {
    struct sigaction sa {};
    sa.sa_handler = remove_temp_files_and_reraise;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESETHAND;
    for (int sig : {SIGTERM, SIGINT, SIGHUP}) {
      // Keep an ignored signal ignored (nohup): the process was not meant to end on it.
      struct sigaction old {};
      if (::sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
      ::sigaction(sig, &sa, nullptr);
    }
  });
}

}  // namespace leeway
