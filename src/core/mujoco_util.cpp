#include "leeway/core/mujoco_util.hpp"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <stdexcept>

#include "leeway/core/error.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/core/mjcf_source.hpp"

namespace leeway {
namespace {

thread_local std::vector<std::string> t_warnings;

void throw_on_error(const char* msg) {
  // MuJoCo calls this instead of exit(); unwinding through its C frames is supported on the
  // platforms we build for (asynchronous unwind tables are the x86-64 and aarch64 default).
  throw InputError(std::string("MuJoCo error: ") + msg);
}

// Thread-safe: each thread appends to its own list. MuJoCo formats some warnings in a process-wide
// buffer before it calls this handler; prevent_contact_warnings keeps those from worker threads.
void collect_warning(const char* msg) { t_warnings.emplace_back(msg); }

}  // namespace

void install_mujoco_error_handlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    mju_user_error = throw_on_error;
    mju_user_warning = collect_warning;
  });
}

std::vector<std::string> take_mujoco_warnings() {
  std::vector<std::string> out;
  out.swap(t_warnings);
  return out;
}

void prevent_contact_warnings(mjData& d) {
  // mj_warning formats its text (in a buffer shared by all threads, mju_warningText) only the first
  // time a warning occurs in an mjData: mark the contact-buffer warnings as already raised.
  for (int w : {mjWARN_CONTACTFULL, mjWARN_CNSTRFULL})
    if (d.warning[w].number == 0) d.warning[w].number = 1;
}

namespace {

// MuJoCo's compiler error on one line: its message spans several ("...\nElement 'key', line 19").
std::string one_line(const char* error) {
  std::string msg;
  for (const char* c = error; *c; ++c) {
    if (*c == '\n') {
      if (c[1] != '\0') msg += "; ";
    } else {
      msg += *c;
    }
  }
  return msg;
}

}  // namespace

ModelPtr load_model_file(const std::string& path) {
  // Documented in the header: without it a malformed file would make MuJoCo exit() the process.
  install_mujoco_error_handlers();
  require_regular_input(path, "file");  // a FIFO would block MuJoCo's reader
  std::ifstream probe(path);
  if (!probe.good()) throw InputError(path + ": cannot open the file (missing or unreadable)");
  probe.close();
  char error[1024] = "";
  mjModel* m = nullptr;
  const bool is_mjb = path.size() > 4 && path.compare(path.size() - 4, 4, ".mjb") == 0;
  if (is_mjb) {
    m = mj_loadModel(path.c_str(), nullptr);
    if (!m) throw InputError(path + ": not a valid MJB file for MuJoCo " + mj_versionString());
  } else {
    // Every numeric attribute is checked before MuJoCo sees it: MuJoCo 2.2.2 reads "nan" as 0
    // (a body, a geom's orientation) with only a warning, and "inf" as it is.
    try {
      // A FIFO, folder or device named as a mesh, texture or height field would block or fail in
      // MuJoCo's reader; a missing one MuJoCo names itself.
      for (const std::string& file : read_mjcf_source(path).files) {
        std::error_code ec;
        if (file == path || !std::filesystem::exists(file, ec)) continue;
        try {
          require_regular_input(file, "file it reads");
        } catch (const InputError& e) {
          throw InputError(path + ": " + e.what());
        }
      }
    } catch (const MjcfSyntaxError&) {
      // MuJoCo's message for a file that is not well-formed XML names the line and element.
      m = mj_loadXML(path.c_str(), nullptr, error, sizeof(error));
      if (!m) throw InputError(path + ": MJCF does not compile: " + one_line(error));
      mj_deleteModel(m);
      throw;
    }
    m = mj_loadXML(path.c_str(), nullptr, error, sizeof(error));
    if (!m) throw InputError(path + ": MJCF does not compile: " + one_line(error));
  }
  return ModelPtr(m);
}

ModelPtr load_model_text(const std::string& xml, const std::string& virtual_path) {
  install_mujoco_error_handlers();
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  if (mj_makeEmptyFileVFS(vfs.get(), virtual_path.c_str(), static_cast<int>(xml.size())) != 0)
    throw std::runtime_error("cannot allocate a MuJoCo virtual file for " + virtual_path);
  std::memcpy(vfs->filedata[vfs->nfile - 1], xml.data(), xml.size());
  char error[1024] = "";
  mjModel* m = mj_loadXML(virtual_path.c_str(), vfs.get(), error, sizeof(error));
  mj_deleteVFS(vfs.get());
  if (!m) throw InputError(virtual_path + ": MJCF does not compile: " + one_line(error));
  return ModelPtr(m);
}

DataPtr make_data(const mjModel& model) {
  mjData* d = mj_makeData(&model);
  if (!d) throw std::bad_alloc();
  return DataPtr(d);
}

std::string object_name(const mjModel& model, mjtObj type, int id) {
  const char* n = mj_id2name(&model, type, id);
  return n ? std::string(n) : std::string();
}

}  // namespace leeway
