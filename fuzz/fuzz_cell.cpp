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
//
// Not leeway's to prevent, so skipped: MuJoCo 2.2.2's compiler allocates what a few bytes ask
// for before leeway sees the model (<size nstack="1000000000"/>: an 8 GB mjData inside
// mj_loadXML; nuser_jnt, nkey: the model's arrays), as it does for heightfield, texture and
// composite sizes. libFuzzer would report every such input as out-of-memory, so the target
// rejects (returns -1: not run, not added to the corpus) an input in which one of those
// attributes holds a number above kMaxCount. Everything else MuJoCo allocates is bounded by the
// input's length.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "fuzz_input.hpp"
#include "leeway/core/cell_defaults.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/mujoco_util.hpp"
#include "leeway/core/params.hpp"
#include "leeway/core/scene.hpp"

namespace {

constexpr double kMaxCount = 1e5;

// True when a size attribute that MuJoCo allocates from (see the top) holds a number beyond
// kMaxCount: every number in the attribute's value is read, so "count" of a composite counts too.
bool asks_mujoco_for_memory(const uint8_t* data, size_t size) {
  static const char* const kNames[] = {"nstack", "nuserdata", "nkey", "nuser_", "njmax",  "nconmax",
                                       "nmocap", "nrow",      "ncol", "width",  "height", "count"};
  const std::string text(reinterpret_cast<const char*>(data), size);
  for (const char* name : kNames)
    for (size_t at = text.find(name); at != std::string::npos; at = text.find(name, at + 1)) {
      const size_t open = text.find_first_of("\"'", at);  // the value's opening quote
      if (open == std::string::npos || text.find('=', at) > open) continue;
      const size_t close = text.find(text[open], open + 1);
      const std::string value = text.substr(open + 1, close == std::string::npos ? close : close - open - 1);
      for (const char* p = value.c_str(); *p;) {
        char* end = nullptr;
        const double v = std::strtod(p, &end);
        if (end == p) {
          ++p;
        } else {
          if (!(std::abs(v) <= kMaxCount)) return true;
          p = end;
        }
      }
    }
  return false;
}

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
  if (asks_mujoco_for_memory(data, size)) return -1;
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
