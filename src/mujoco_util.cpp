#include "leeway/mujoco_util.hpp"

#include <fstream>
#include <mutex>

#include "leeway/error.hpp"

namespace leeway {
namespace {

thread_local std::vector<std::string> t_warnings;

void throw_on_error(const char* msg) {
  // MuJoCo calls this instead of exit(); unwinding through its C frames is supported on the
  // platforms we build for (asynchronous unwind tables are the x86-64 and aarch64 default).
  throw InputError(std::string("MuJoCo error: ") + msg);
}

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

ModelPtr load_model_file(const std::string& path) {
  // Documented in the header: without it a malformed file would make MuJoCo exit() the process.
  install_mujoco_error_handlers();
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
    m = mj_loadXML(path.c_str(), nullptr, error, sizeof(error));
    if (!m) {
      // One line: MuJoCo's message spans several ("...\nElement 'key', line 19").
      std::string msg;
      for (const char* c = error; *c; ++c) {
        if (*c == '\n') {
          if (c[1] != '\0') msg += "; ";
        } else {
          msg += *c;
        }
      }
      throw InputError(path + ": MJCF does not compile: " + msg);
    }
  }
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
