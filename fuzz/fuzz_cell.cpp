// libFuzzer target: a workcell (MJCF) file through Scene::load, the cell's defaults and a first
// collision query, as every leeway subcommand that takes a cell starts (docs/testing.md, "Fuzzing").
//
// Contract: Scene::load (MuJoCo's XML parser and compiler, then leeway's recognition of the robot,
// geoms, sites and keyframes, docs/mjcf-conventions.md), apply_cell_defaults and RobotState's
// in_collision and clearance at the cell's keyframes either succeed or throw leeway::InputError
// naming the file (scene.hpp, cell_defaults.hpp, kinematics.hpp @throws). MuJoCo's mju_error goes
// through install_mujoco_error_handlers' handler, which throws InputError instead of exiting; a
// MuJoCo error that escapes without the file name is a finding too. Anything else is a finding: another
// exception (std::logic_error from LEEWAY_DEMAND, nlohmann or std exceptions, std::bad_alloc), a
// crash, a sanitizer report, a leak, an input that runs longer than -timeout or allocates beyond
// -rss_limit_mb.
//
// The input is written to TMP/leeway-fuzz-XXXXXX/workcells/cell.xml beside a link robots -> the
// source tree's mjcf/robots, so that the bundled cells' <include file="../robots/..."/> resolve.
// MuJoCo itself (Debian's libmujoco, not instrumented) gives no coverage feedback: the fuzzer is
// guided by leeway's code only, and a memory error inside MuJoCo shows only as a crash.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "fuzz_input.hpp"
#include "leeway/cell_defaults.hpp"
#include "leeway/kinematics.hpp"
#include "leeway/mujoco_util.hpp"
#include "leeway/params.hpp"
#include "leeway/scene.hpp"

namespace {

const leeway::fuzz::InputFile& input() {
  static const leeway::fuzz::InputFile file("workcells/cell.xml");
  return file;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  leeway::install_mujoco_error_handlers();
  std::filesystem::create_directory_symlink(leeway::fuzz::kSourceDir + "/mjcf/robots",
                                            input().dir() / "robots");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = input().write(data, size);
  try {
    const leeway::Scene scene = leeway::Scene::load(path);
    leeway::Params params = leeway::preset_params("leeway");
    leeway::apply_cell_defaults(scene, params);
    leeway::RobotState state(scene);
    std::vector<Eigen::VectorXd> poses = {leeway::default_ik_seed(scene)};
    for (const auto& k : scene.keyframes())
      if (poses.size() < 4) poses.push_back(k.q);
    for (const auto& q : poses) {
      state.in_collision(q);
      state.clearance(q);
    }
  } catch (const leeway::InputError& e) {
    leeway::fuzz::require_names_file(e, path);
  }
  leeway::take_mujoco_warnings();  // per-thread list: empty it, or it grows with every input
  return 0;
}
