// libFuzzer target: a path file through read_path for the bundled cell mjcf/workcells/dallara.xml
// (six hinge joints j1..j6), loaded once (docs/testing.md, "Fuzzing").
//
// Contract: read_path (nominal_path.hpp) returns at least two configurations of the robot's size,
// each finite and within the joint limits, or throws leeway::InputError naming the file and the
// mismatch: unreadable file or malformed JSON (as read_params), not a path file, another "format",
// other joints, fewer than two waypoints, a wrong number of values, a value that is not a finite
// number or is outside the limits (nlohmann's type errors are turned into InputError "unexpected
// content"). Anything else is a finding: another exception, a crash, a sanitizer report, a leak, a
// timeout, or a result that breaks the guarantees above.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "fuzz_input.hpp"
#include "leeway/path/nominal_path.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  leeway::fuzz::dallara_scene();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const leeway::fuzz::InputFile input("path.json");
  const std::string& path = input.write(data, size);
  const leeway::Scene& scene = leeway::fuzz::dallara_scene();
  try {
    const auto waypoints = leeway::read_path(path, scene);
    bool ok = waypoints.size() >= 2;
    for (const auto& q : waypoints) {
      ok = ok && q.size() == scene.dof();
      for (int k = 0; ok && k < scene.dof(); ++k) {
        const auto& j = scene.joints()[static_cast<size_t>(k)];
        ok = std::isfinite(q[k]) && j.lower <= q[k] && q[k] <= j.upper;
      }
    }
    if (!ok) {
      std::fprintf(stderr, "leeway fuzz: read_path returned a path outside its guarantees\n");
      std::abort();
    }
  } catch (const leeway::InputError& e) {
    leeway::fuzz::require_names_file(e, path);
  }
  return 0;
}
