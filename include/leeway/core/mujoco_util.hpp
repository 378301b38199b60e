#pragma once
//! @file mujoco_util.hpp
//! Ownership of MuJoCo objects, and MuJoCo's error/warning callbacks turned into C++ behaviour.

#include <mujoco/mujoco.h>

#include <memory>
#include <string>
#include <vector>

namespace leeway {

//! Deletes an mjModel.
struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
//! Deletes an mjData.
struct DataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using ModelPtr = std::unique_ptr<mjModel, ModelDeleter>;
using DataPtr = std::unique_ptr<mjData, DataDeleter>;

//! Installs process-wide MuJoCo handlers: mju_error throws InputError (no abort), warnings are
//! collected per thread (take_mujoco_warnings) instead of being written to MUJOCO_LOG.TXT.
//! Idempotent and thread-safe. This changes global state (MuJoCo's mju_user_error and
//! mju_user_warning), so programs call it once at the start of main(). The library also calls it,
//! idempotently, before it compiles a model (load_model_file) or makes a RobotState or a
//! VolumeModel, because MuJoCo's default handler would exit() the process on bad input; a program
//! that installs its own handlers must do so after its first use of leeway.
void install_mujoco_error_handlers();

//! Returns and clears the MuJoCo warnings raised on this thread since the last call.
std::vector<std::string> take_mujoco_warnings();

//! Marks MuJoCo's contact- and constraint-buffer warnings as already raised in `d`, so that
//! mj_collision on a full buffer (still "in collision": ncon > 0) neither formats nor reports a
//! warning. MuJoCo formats warning text in one process-wide buffer, so worker threads must not raise
//! warnings; leeway calls this before every mj_collision.
void prevent_contact_warnings(mjData& d);

//! Compiles an MJCF (or MJB) file; an MJCF file's numeric attributes, included files' too, are
//! checked first (read_mjcf_source).
//! @throws InputError naming the file when it is missing, unreadable or does not compile, or naming
//! the file, element, attribute and value of a number that is not finite.
ModelPtr load_model_file(const std::string& path);

//! Compiles MJCF text as if it were the file `virtual_path` (through MuJoCo's virtual file system),
//! so that its relative includes and asset paths resolve against that file's folder.
//! @throws InputError "VIRTUAL_PATH: MJCF does not compile: ..." (one line) when MuJoCo rejects it.
ModelPtr load_model_text(const std::string& xml, const std::string& virtual_path);

//! Allocates an mjData for a model. @throws std::bad_alloc when MuJoCo cannot allocate it.
DataPtr make_data(const mjModel& model);

//! Name of a MuJoCo object, or "" when it has none.
std::string object_name(const mjModel& model, mjtObj type, int id);

}  // namespace leeway
