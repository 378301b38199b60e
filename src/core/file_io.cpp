#include "leeway/core/file_io.hpp"

#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <random>
#include <streambuf>

#include "leeway/core/error.hpp"

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

// Claims a slot of the table for `path`; -1 when the table is full or the path too long (the write
// still happens, only its clean-up on a signal is lost).
int register_temp(const std::string& path) {
  if (path.size() >= kTempPathMax) return -1;
  for (int i = 0; i < kTempSlots; ++i) {
    bool expected = false;
    if (g_temp_slots[i].used.compare_exchange_strong(expected, true)) {
      std::memcpy(g_temp_slots[i].path, path.c_str(), path.size() + 1);
      g_temp_slots[i].ready.store(true);
      return i;
    }
  }
  return -1;
}

void unregister_temp(int slot) {
  if (slot < 0) return;
  g_temp_slots[slot].ready.store(false);
  g_temp_slots[slot].used.store(false);
}

// SIGTERM, SIGINT and SIGHUP held back while a temporary file is created and registered, so that
// the handler never misses a file of ours nor removes one that is not (a name that already
// existed).
class BlockCleanupSignals {
 public:
  BlockCleanupSignals() {
    sigset_t set;
    sigemptyset(&set);
    for (int sig : {SIGTERM, SIGINT, SIGHUP}) sigaddset(&set, sig);
    ::pthread_sigmask(SIG_BLOCK, &set, &old_);
  }
  ~BlockCleanupSignals() { ::pthread_sigmask(SIG_SETMASK, &old_, nullptr); }
  BlockCleanupSignals(const BlockCleanupSignals&) = delete;
  BlockCleanupSignals& operator=(const BlockCleanupSignals&) = delete;

 private:
  sigset_t old_;
};

// 48 random bits as 12 hex digits: a temporary name another user cannot guess and plant first.
std::string random_suffix() {
  std::uint64_t bits = 0;
  if (::getrandom(&bits, sizeof bits, 0) != static_cast<ssize_t>(sizeof bits)) {
    std::random_device rd;
    bits = (static_cast<std::uint64_t>(rd()) << 32) ^ rd();
  }
  char text[17];
  std::snprintf(text, sizeof text, "%012llx", static_cast<unsigned long long>(bits & 0xffffffffffffULL));
  return text;
}

std::string reason_of(int err) { return std::strerror(err); }

// What lstat finds at `path` (without following a final link); false when nothing is there.
bool lstat_path(const std::string& path, struct stat& st) { return ::lstat(path.c_str(), &st) == 0; }

// The message part for a path that is not a regular file, or "" for a regular file.
std::string not_regular(const struct stat& st) {
  if (S_ISREG(st.st_mode)) return "";
  if (S_ISLNK(st.st_mode))
    return "the output file is a symbolic link; leeway replaces output files whole, which would "
           "replace the link rather than the file it points to: name that file, or remove the link";
  fs::file_status status;
  if (S_ISDIR(st.st_mode))
    status = fs::file_status(fs::file_type::directory);
  else if (S_ISFIFO(st.st_mode))
    status = fs::file_status(fs::file_type::fifo);
  else if (S_ISCHR(st.st_mode))
    status = fs::file_status(fs::file_type::character);
  else if (S_ISBLK(st.st_mode))
    status = fs::file_status(fs::file_type::block);
  else if (S_ISSOCK(st.st_mode))
    status = fs::file_status(fs::file_type::socket);
  return std::string("the output file is ") + kind_of(status) +
         ", not a regular file; leeway only writes regular files";
}

void fsync_folder(const fs::path& folder) {
  const int dir = ::open(folder.empty() ? "." : folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir < 0) return;
  ::fsync(dir);  // the rename on disk too; a file system that cannot is no reason to fail
  ::close(dir);
}

}  // namespace

void require_regular_input(const std::string& path, const std::string& what) {
  std::error_code ec;
  const fs::file_status s = fs::status(path, ec);  // follows links; never opens the file
  if (path.empty()) throw InputError("the " + what + " name is empty");
  if (ec || !fs::exists(s)) throw InputError(path + ": cannot open the " + what + " (missing or unreadable)");
  if (!fs::is_regular_file(s))
    throw InputError(path + ": the " + what + " is " + kind_of(s) + ", not a regular file");
}

void require_outputs(const std::vector<OutputFile>& outputs, const std::vector<std::string>& inputs) {
  for (const OutputFile& o : outputs) {
    if (o.path.empty()) continue;
    const std::string named = o.option.empty() ? o.path : o.option + " " + o.path;
    if (!o.extensions.empty()) {
      const std::string ext = fs::path(o.path).extension().string();
      if (std::find(o.extensions.begin(), o.extensions.end(), ext) == o.extensions.end()) {
        std::string listed;
        for (const auto& e : o.extensions) listed += (listed.empty() ? "" : " or ") + e;
        throw InputError(named + ": the file name must end in " + listed);
      }
    }
    const fs::path folder =
        fs::path(o.path).has_parent_path() ? fs::path(o.path).parent_path() : fs::path(".");
    std::error_code ec;
    if (!fs::is_directory(folder, ec) || ::access(folder.c_str(), W_OK) != 0)
      throw InputError(named + ": cannot write there (folder '" + folder.string() +
                       "' missing or not writable)");
    // A name the folder cannot hold would fail only when the finished file is moved into place.
    const long queried = ::pathconf(folder.c_str(), _PC_NAME_MAX);
    const size_t name_max = queried > 0 ? static_cast<size_t>(queried) : 255;
    const size_t name_bytes = fs::path(o.path).filename().string().size();
    if (name_bytes > name_max)
      throw InputError(named + ": the file name has " + std::to_string(name_bytes) + " bytes; folder '" +
                       folder.string() + "' allows at most " + std::to_string(name_max));
    if (fs::absolute(o.path, ec).string().size() >= PATH_MAX)
      throw InputError(named + ": the path is longer than the system allows (" +
                       std::to_string(PATH_MAX - 1) + " bytes)");
    struct stat st;
    if (!lstat_path(o.path, st)) continue;
    if (const std::string why = not_regular(st); !why.empty()) throw InputError(named + ": " + why);
    for (const auto& input : inputs) {
      if (input.empty()) continue;
      if (fs::equivalent(o.path, input, ec) && !ec)
        throw InputError(named + ": the output file is the input file " + input +
                         "; it would be overwritten");
    }
  }
  // Two outputs naming one file: one of them would be lost. Paths that do not exist yet are
  // compared by their canonical form (links and `..` in the folders resolved).
  for (size_t i = 0; i < outputs.size(); ++i)
    for (size_t k = i + 1; k < outputs.size(); ++k) {
      const OutputFile& a = outputs[i];
      const OutputFile& b = outputs[k];
      if (a.path.empty() || b.path.empty()) continue;
      std::error_code ea, eb, ee;
      const bool same = fs::weakly_canonical(a.path, ea) == fs::weakly_canonical(b.path, eb) ||
                        (fs::equivalent(a.path, b.path, ee) && !ee);
      if (same && !ea && !eb)
        throw InputError(a.option + " and " + b.option + " name the same file " + a.path +
                         "; one output would be lost");
    }
}

TempFile::TempFile(const std::string& target, unsigned mode) : target_(target) {
  const fs::path t(target);
  // Short enough that the hidden name stays within the 255 bytes a file name may have.
  const std::string stem = t.filename().string().substr(0, 200);
  const BlockCleanupSignals blocked;
  for (int attempt = 0; attempt < 100; ++attempt) {
    const fs::path candidate = t.parent_path() / ("." + stem + "." + random_suffix());
    // O_EXCL: never an existing file; O_NOFOLLOW: never through a link planted at the name.
    const int fd = ::open(candidate.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC,
                          static_cast<mode_t>(mode));
    if (fd >= 0) {
      fd_ = fd;
      path_ = candidate.string();
      slot_ = register_temp(path_);
      return;
    }
    if (errno != EEXIST) break;
  }
  throw InputError(
      target + ": cannot write the output file (folder missing or not writable: " + reason_of(errno) + ")");
}

TempFile::~TempFile() {
  const BlockCleanupSignals blocked;  // the file and its slot go together
  if (fd_ >= 0) ::close(fd_);
  if (!done_ && !path_.empty()) ::unlink(path_.c_str());
  unregister_temp(slot_);
}

void TempFile::set_mode(unsigned mode) {
  LEEWAY_DEMAND(fd_ >= 0);
  ::fchmod(fd_, static_cast<mode_t>(mode));  // best effort: the content matters more than the mode
}

void TempFile::write(const std::string& text) {
  LEEWAY_DEMAND(fd_ >= 0);
  for (size_t done = 0; done < text.size();) {
    const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw InputError(target_ + ": writing the output file failed (" + reason_of(errno) + ")");
    done += static_cast<size_t>(n);
  }
}

void TempFile::close() {
  if (fd_ < 0) return;
  // On disk before any rename, so that a crash leaves the old file or the new one, never an empty one.
  if (::fsync(fd_) != 0) {
    const int err = errno;
    ::close(fd_);
    fd_ = -1;
    throw InputError(target_ + ": writing the output file to disk failed (" + reason_of(err) + ")");
  }
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0)
    throw InputError(target_ + ": writing the output file failed (" + reason_of(errno) + ")");
}

void TempFile::commit() {
  close();
  if (::rename(path_.c_str(), target_.c_str()) != 0)
    throw InputError(target_ + ": cannot move the output file into place (" + reason_of(errno) + ")");
  done_ = true;
  fsync_folder(fs::path(target_).parent_path());
}

void write_file_atomic(const std::string& path, const std::string& text) {
  if (path.empty()) throw InputError("the output file name is empty");
  struct stat st;
  const bool exists = lstat_path(path, st);
  if (exists)
    if (const std::string why = not_regular(st); !why.empty()) throw InputError(path + ": " + why);
  TempFile tmp(path);
  // A file replaced keeps its permission bits (a private 0600 file stays private).
  if (exists) tmp.set_mode(st.st_mode & 07777);
  tmp.write(text);
  tmp.commit();
}

// The stream of a StreamingOutput: characters collect in `pending` and go to the file at every
// flush (and when 64 KiB have collected).
struct StreamingOutput::Impl : std::streambuf {
  std::string path, what;
  int fd = -1;
  bool created = false, truncated = false;
  std::string pending;
  std::ostream out{this};

  void write_pending() {
    for (size_t done = 0; done < pending.size();) {
      const ssize_t n = ::write(fd, pending.data() + done, pending.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        pending.clear();
        throw InputError(what + " " + path + ": writing the file failed (" + reason_of(errno) + ")");
      }
      done += static_cast<size_t>(n);
    }
    pending.clear();
  }
  int_type overflow(int_type c) override {
    if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
    pending += traits_type::to_char_type(c);
    if (pending.size() >= 65536) write_pending();
    return c;
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    pending.append(s, static_cast<size_t>(n));
    if (pending.size() >= 65536) write_pending();
    return n;
  }
  int sync() override {
    write_pending();
    return 0;
  }
};

StreamingOutput::StreamingOutput() = default;

StreamingOutput::StreamingOutput(const std::string& path, const std::string& what)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.path = path;
  s.what = what;
  const std::string named = what + " " + path;
  // First without O_CREAT, to know whether the file is ours to remove again; O_NOFOLLOW refuses a
  // link at the name, so the rows never land in the file it points to.
  s.fd = ::open(path.c_str(), O_WRONLY | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK);
  if (s.fd < 0 && errno == ENOENT) {
    s.fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    s.created = s.fd >= 0;
  }
  if (s.fd < 0) {
    const int err = errno;
    struct stat st;
    if (lstat_path(path, st))
      if (const std::string why = not_regular(st); !why.empty()) throw InputError(named + ": " + why);
    throw InputError(named + ": cannot write the file (" + reason_of(err) + ")");
  }
  struct stat st {};
  if (::fstat(s.fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(s.fd);
    s.fd = -1;
    throw InputError(named + ": " + not_regular(st));
  }
  ::fcntl(s.fd, F_SETFL, ::fcntl(s.fd, F_GETFL) & ~O_NONBLOCK);
  if (::flock(s.fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    ::close(s.fd);
    s.fd = -1;
    if (err == EWOULDBLOCK)
      throw InputError(named +
                       ": the file is locked by another process writing it (another run with the "
                       "same " +
                       what + "?); give another file or wait until that run has ended");
    throw InputError(named + ": cannot lock the file (" + reason_of(err) + ")");
  }
  s.out.exceptions(std::ios::badbit);  // a failed write throws the InputError above
}

StreamingOutput::~StreamingOutput() {
  if (!impl_ || impl_->fd < 0) return;
  Impl& s = *impl_;
  if (!s.pending.empty()) {
    try {
      s.write_pending();
    } catch (const InputError&) {
      // Nothing to report to from a destructor; the rows written so far stay.
    }
  }
  if (s.created && !s.truncated) ::unlink(s.path.c_str());
  ::close(s.fd);  // releases the lock
}

StreamingOutput::StreamingOutput(StreamingOutput&& other) noexcept = default;
StreamingOutput& StreamingOutput::operator=(StreamingOutput&& other) noexcept {
  if (this != &other) {
    StreamingOutput old(std::move(*this));  // closes this one's file first
    impl_ = std::move(other.impl_);
  }
  return *this;
}

bool StreamingOutput::is_open() const { return impl_ && impl_->fd >= 0; }

void StreamingOutput::truncate() {
  LEEWAY_DEMAND(is_open());
  Impl& s = *impl_;
  s.pending.clear();
  if (::ftruncate(s.fd, 0) != 0 || ::lseek(s.fd, 0, SEEK_SET) != 0)
    throw InputError(s.what + " " + s.path + ": cannot empty the file (" + reason_of(errno) + ")");
  s.truncated = true;
}

std::ostream& StreamingOutput::stream() {
  LEEWAY_DEMAND(is_open());
  return impl_->out;
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
