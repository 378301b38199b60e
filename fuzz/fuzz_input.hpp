#pragma once
// The fuzz targets' shared pieces (docs/testing.md, "Fuzzing"): leeway's readers take file paths,
// so each input is written to one temporary file per process, reused for every input and removed
// at exit; and the contract every target checks: a reader succeeds or throws leeway::InputError
// whose message names the file. Anything else escapes the target and libFuzzer reports it (an
// uncaught exception ends in std::terminate, an abort with the exception's type and message).

#include <stdlib.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "leeway/core/error.hpp"
#include "leeway/core/mujoco_util.hpp"
#include "leeway/core/scene.hpp"

namespace leeway::fuzz {

//! The source tree (set by fuzz/CMakeLists.txt): the targets load bundled cells from it.
inline const std::string kSourceDir = LEEWAY_SOURCE_DIR;

//! A private folder TMPDIR/leeway-fuzz-XXXXXX (TMPDIR or /tmp) holding the input file `name` (a
//! relative path: its folders are made); removed with everything in it when the process exits normally (a
//! crash leaves it behind, with libFuzzer's reproducer written elsewhere).
class InputFile {
 public:
  explicit InputFile(const std::string& name) {
    const char* tmp = std::getenv("TMPDIR");
    std::string tmpl = std::string(tmp && *tmp ? tmp : "/tmp") + "/leeway-fuzz-XXXXXX";
    if (!::mkdtemp(tmpl.data())) {
      std::perror("leeway fuzz: mkdtemp");
      std::abort();
    }
    dir_ = tmpl;
    std::filesystem::create_directories((dir_ / name).parent_path());
    path_ = (dir_ / name).string();
  }
  ~InputFile() {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  //! The folder, for files an input may refer to (a cell's robot include, a URDF's meshes).
  const std::filesystem::path& dir() const { return dir_; }
  const std::string& path() const { return path_; }

  //! Replaces the file's content with the input; returns its path.
  const std::string& write(const uint8_t* data, size_t size) const {
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    out.close();
    if (!out) {
      std::perror(("leeway fuzz: cannot write " + path_).c_str());
      std::abort();
    }
    return path_;
  }

 private:
  std::filesystem::path dir_;
  std::string path_;
};

//! The contract's second half: an InputError names the file it is about ("PATH: ..."). A message
//! that does not is a finding: the user would not know which file to mend.
inline void require_names_file(const InputError& e, const std::string& path) {
  const std::string message = e.what();
  if (message.find(path) == std::string::npos) {
    std::fprintf(stderr, "leeway fuzz: InputError without the file name '%s': %s\n", path.c_str(),
                 message.c_str());
    std::abort();
  }
}

//! The bundled Dallara cell (six hinge joints j1..j6), loaded once per process: the scene the
//! bounds and path readers check their files against. Called from LLVMFuzzerInitialize.
inline const Scene& dallara_scene() {
  static const Scene scene = [] {
    install_mujoco_error_handlers();
    return Scene::load(kSourceDir + "/mjcf/workcells/dallara.xml");
  }();
  return scene;
}

}  // namespace leeway::fuzz
