// libFuzzer target: a bounds file through read_bounds for the bundled cell mjcf/workcells/dallara.xml
// (six hinge joints j1..j6), loaded once (docs/testing.md, "Fuzzing").
//
// Contract: read_bounds (bounds_file.hpp) returns one WaypointBounds per waypoint, each within the
// joint limits with lower <= q <= upper, or throws leeway::InputError naming the file and the
// mismatch: unreadable file or malformed JSON (as read_params), not a bounds file, another
// "format", other joints, wrong sizes or types (nlohmann's type errors are turned into InputError
// "unexpected content"), bounds outside the limits, a nominal outside its bounds, an unknown
// collapsed joint; read_bounds_trajectory also refuses format-2 times that are missing, not finite,
// not starting at 0, decreasing, or an s other than the index, and its trajectory's box at any s
// contains the nominal value there. Anything else is a finding: another exception, a crash, a sanitizer
// report, a leak, a timeout, or a result that breaks the guarantees above.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "fuzz_input.hpp"
#include "leeway/io/bounds_file.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  leeway::fuzz::dallara_scene();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const leeway::fuzz::InputFile input("bounds.json");
  const std::string& path = input.write(data, size);
  const leeway::Scene& scene = leeway::fuzz::dallara_scene();
  try {
    const auto bounds = leeway::read_bounds(path, scene);
    for (const auto& w : bounds) {
      bool ok = w.q.size() == scene.dof() && w.lower.size() == scene.dof() && w.upper.size() == scene.dof() &&
                static_cast<int>(w.collapsed.size()) == scene.dof();
      for (int k = 0; ok && k < scene.dof(); ++k) {
        const auto& j = scene.joints()[static_cast<size_t>(k)];
        ok = j.lower <= w.lower[k] && w.lower[k] <= w.q[k] && w.q[k] <= w.upper[k] && w.upper[k] <= j.upper;
      }
      if (!ok) {
        std::fprintf(stderr, "leeway fuzz: read_bounds returned bounds outside its guarantees\n");
        std::abort();
      }
    }
  } catch (const leeway::InputError& e) {
    leeway::fuzz::require_names_file(e, path);
  }
  try {
    const leeway::BoundsTrajectory tr = leeway::read_bounds_trajectory(path, scene);
    for (double s : {0.0, 0.5 * tr.s_end(), 0.37 * tr.s_end(), tr.s_end()}) {
      const leeway::BoundsStage b = tr.at_s(s);
      // Interpolated apart, the three may differ from exact arithmetic by rounding: a few ulps.
      const Eigen::ArrayXd tol = 1e-12 * (1 + b.nominal.array().abs());
      if (!((b.lower.array() <= b.nominal.array() + tol).all() &&
            (b.nominal.array() <= b.upper.array() + tol).all()) ||
          !(tr.t_at_s(s) >= 0 && tr.t_at_s(s) <= tr.duration())) {
        std::fprintf(stderr, "leeway fuzz: a trajectory box at s = %g leaves out its nominal value or time\n",
                     s);
        std::abort();
      }
    }
  } catch (const leeway::InputError& e) {
    leeway::fuzz::require_names_file(e, path);
  }
  return 0;
}
