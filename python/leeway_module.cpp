// The Python module `leeway` (docs/python.md): cells, bounds between two keyframes, bounds files, the
// bounds as a controller reads them (BoundsTrajectory) and the Confidence Factor, over the library's
// public API. Units are SI: metres, radians, seconds.

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "core/json_io.hpp"
#include "leeway/core/bounds_trajectory.hpp"
#include "leeway/core/cell_defaults.hpp"
#include "leeway/core/check.hpp"
#include "leeway/core/confidence.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/core/mujoco_util.hpp"
#include "leeway/core/params.hpp"
#include "leeway/core/pipeline.hpp"
#include "leeway/core/scene.hpp"
#include "leeway/core/volume_world.hpp"
#include "leeway/io/bounds_file.hpp"
#include "leeway/path/nominal_path.hpp"
#include "leeway/path/path_check.hpp"

namespace py = pybind11;
using nlohmann::json;

namespace leeway::python {
namespace {

// Most worker threads a call accepts, as the command line's --threads.
constexpr int kMaxThreads = 256;

// A bounded path as Python sees it: the trajectory, its joints, and the bounds file's JSON (written
// by save()). Immutable; the trajectory is shared, never copied.
struct Bounds {
  std::vector<std::string> joints;
  std::shared_ptr<const BoundsTrajectory> trajectory;
  json file;                      // the bounds file: from the run, or as read
  std::optional<bool> certified;  // certified_region.proven; none when the file does not say
};

// The nominal path between the keyframes collides: a negative outcome, not bad input (the command
// line's exit 1). Python's leeway.CollisionError, a RuntimeError.
struct NominalCollision : std::runtime_error {
  using std::runtime_error::runtime_error;
};

int resolve_threads(int threads) {
  if (threads == 0) return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  if (threads < 1 || threads > kMaxThreads)
    throw InputError("threads " + std::to_string(threads) + " must be from 1 to " +
                     std::to_string(kMaxThreads) + " (0: one per hardware thread)");
  return threads;
}

std::vector<std::string> joint_names(const Scene& scene) {
  std::vector<std::string> names;
  for (const auto& j : scene.joints()) names.push_back(j.name);
  return names;
}

// JSON to Python objects through the standard library's json module (dicts, lists, numbers).
py::object to_python(const json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

// A Python value of a keyword parameter as JSON (bool before int: True is an int in Python). numpy's
// scalars count as numbers too (np.int64 through __index__, np.float64 through __float__).
json to_json_value(const std::string& name, const py::handle& h) {
  const auto v = py::reinterpret_borrow<py::object>(h);
  if (py::isinstance<py::bool_>(v) || py::isinstance(v, py::module_::import("numpy").attr("bool_")))
    return py::bool_(v).cast<bool>();
  if (py::isinstance<py::int_>(v) || py::hasattr(v, "__index__")) return py::int_(v).cast<long long>();
  if (py::isinstance<py::float_>(v) || py::hasattr(v, "__float__")) return py::float_(v).cast<double>();
  if (py::isinstance<py::str>(v)) return v.cast<std::string>();
  throw InputError("parameter '" + name + "': " + std::string(py::str(py::type::of(v).attr("__name__"))) +
                   " is not a number, bool or string");
}

// The dotted keyword parameters ("height_map.max_cells") as a parameter file's JSON object
// ({"height_map": {"max_cells": ...}}), which params_from_json checks name by name.
json params_object(const py::kwargs& params) {
  json out = json::object();
  for (const auto& [key, value] : params) {
    const std::string name = py::str(key);
    json* node = &out;
    std::size_t start = 0;
    for (std::size_t dot = name.find('.'); dot != std::string::npos; dot = name.find('.', start)) {
      node = &(*node)[name.substr(start, dot - start)];
      if (!node->is_object() && !node->is_null())
        throw InputError("parameter '" + name + "' is given along with a parameter it would replace");
      start = dot + 1;
    }
    (*node)[name.substr(start)] = to_json_value(name, value);
  }
  return out;
}

// certified_region.proven of a bounds file, when it says.
std::optional<bool> proven(const json& file) {
  const auto region = file.find("certified_region");
  if (region == file.end() || !region->is_object()) return std::nullopt;
  const auto p = region->find("proven");
  if (p == region->end() || !p->is_boolean()) return std::nullopt;
  return p->get<bool>();
}

// An N x n float64 array of one member of every waypoint.
template <class Member>
py::array_t<double> waypoint_matrix(const Bounds& b, Member member) {
  const auto& w = b.trajectory->waypoints();
  const auto n = static_cast<py::ssize_t>(b.trajectory->dof());
  py::array_t<double> out({static_cast<py::ssize_t>(w.size()), n});
  auto m = out.mutable_unchecked<2>();
  for (std::size_t i = 0; i < w.size(); ++i)
    for (py::ssize_t j = 0; j < n; ++j) m(static_cast<py::ssize_t>(i), j) = (w[i].*member)[j];
  return out;
}

Bounds bounds_between(const std::shared_ptr<Scene>& scene_ptr, const std::string& from, const std::string& to,
                      const std::string& preset, const std::optional<std::string>& safety, int waypoints,
                      int threads, const py::kwargs& params) {
  const Scene& scene = *scene_ptr;
  const json overrides = params_object(params);  // with the GIL: reads Python objects
  py::gil_scoped_release release;
  // As `leeway bounds`: the preset, the cell's own defaults, the parameters given, then safety.
  ParamLayers layers;
  layers.preset = preset;
  if (!overrides.empty()) {
    layers.object = overrides;
    layers.object_source = "bounds() keyword parameters";
  }
  if (safety) layers.safety = parse_safety_mode(*safety, "safety");
  Params p = compose_params(scene, layers);
  p.validate();
  threads = resolve_threads(threads);
  if (waypoints < 2) throw InputError("waypoints " + std::to_string(waypoints) + " must be >= 2");
  // The method assumes a collision-free nominal path: it is checked densely first. Keyframes only,
  // and no planning around a collision (leeway bounds does that).
  if (is_gripper_goal(from) || is_gripper_goal(to))
    throw InputError("bounds(): from and to must be keyframes, got '" + from + "' and '" + to + "'");
  PathRequest request;
  request.from = from;
  request.to = to;
  request.waypoints = waypoints;
  request.plan_around = false;
  const NominalPath nominal = resolve_nominal_path(scene, request);
  if (!nominal.ok())
    throw NominalCollision(nominal.message + " (leeway bounds plans around it; bound a planned path there)");
  const std::vector<Eigen::VectorXd>& path = nominal.waypoints;
  VolumeModel world(scene, VolumeModel::capacity_for(scene, p.height_map.max_cells));
  const BoundsRun run = compute_bounds(scene, world, path, p, threads);
  Bounds b;
  b.joints = joint_names(scene);
  b.file = bounds_json(scene, run, p);
  b.file["nominal_path"] = nominal.record;
  b.certified = proven(b.file);
  b.trajectory = std::make_shared<const BoundsTrajectory>(scene, run.bounds);
  return b;
}

Bounds read_bounds_py(const std::string& path, const std::shared_ptr<Scene>& scene) {
  py::gil_scoped_release release;
  Bounds b;
  b.file = detail::read_json_file(path, "bounds file");
  if (scene) {
    b.joints = joint_names(*scene);
    b.trajectory = std::make_shared<const BoundsTrajectory>(read_bounds_trajectory(path, *scene));
  } else {
    BoundsFile f = read_bounds_file(path);
    b.joints = std::move(f.joints);
    b.trajectory = std::make_shared<const BoundsTrajectory>(std::move(f.trajectory));
  }
  b.certified = proven(b.file);
  return b;
}

py::dict sample_py(const Bounds& b, double dt) {
  const BoundsTrajectory& tr = *b.trajectory;
  const long rows = tr.sample_count(dt);
  const auto m = static_cast<py::ssize_t>(rows), n = static_cast<py::ssize_t>(tr.dof());
  py::array_t<double> t(m), s(m), nominal({m, n}), lower({m, n}), upper({m, n});
  double *pt = t.mutable_data(), *ps = s.mutable_data(), *pn = nominal.mutable_data(),
         *pl = lower.mutable_data(), *pu = upper.mutable_data();
  {
    // Rows as BoundsTrajectory::sample gives them, written straight into the arrays (row-major).
    py::gil_scoped_release release;
    const double end = tr.duration();
    for (long i = 0; i < rows; ++i) {
      const double ti = i == rows - 1 ? end : std::min(end, static_cast<double>(i) * dt);
      const auto off = static_cast<std::ptrdiff_t>(i) * n;
      Eigen::Map<Eigen::VectorXd> nom(pn + off, n), lo(pl + off, n), up(pu + off, n);
      pt[i] = ti;
      ps[i] = tr.s_at_t(ti);
      tr.at_t(ti, nom, lo, up);
    }
  }
  py::dict out;
  out["t"] = t;
  out["s"] = s;
  out["nominal"] = nominal;
  out["lower"] = lower;
  out["upper"] = upper;
  return out;
}

py::dict confidence_py(const std::shared_ptr<Scene>& scene, const Bounds& b, int samples, int windows,
                       std::uint64_t seed, int threads, bool self) {
  if (b.joints != joint_names(*scene))
    throw InputError("the bounds' joints do not match the cell " + scene->source() + "'s joints");
  CfParams params;
  params.samples = samples;
  params.windows = windows;
  params.seed = seed;
  params.self = self;
  CfResult r;
  {
    py::gil_scoped_release release;
    r = confidence_factor(*scene, *b.trajectory, params, resolve_threads(threads));
  }
  py::dict out;
  out["cf"] = r.cf;
  out["ci95"] = py::make_tuple(r.ci_low, r.ci_high);
  out["samples"] = r.samples;
  out["collisions"] = r.collisions;
  out["obstacle_collisions"] = r.obstacle_collisions;
  out["self_collisions"] = r.self_collisions;
  out["any_collisions"] = r.any_collisions;
  out["counts"] = self ? "obstacle and self collisions" : "obstacle collisions";
  out["worst_window"] = r.worst_window;
  out["worst_window_cf"] = r.worst_window_cf;
  out["window_cf"] = r.window_cf;
  out["timed"] = r.timed;
  out["duration"] = r.duration;
  return out;
}

}  // namespace
}  // namespace leeway::python

PYBIND11_MODULE(leeway, m) {
  using namespace leeway;
  using namespace leeway::python;
  m.doc() =
      "leeway: collision-free joint intervals around a robot's nominal path (docs/python.md).\n"
      "Units are SI: metres, radians (hinge joints), seconds. Bad input raises ValueError with leeway's\n"
      "message; a colliding nominal path raises leeway.CollisionError (a RuntimeError).";

  // MuJoCo's default error handler would exit() the process: leeway's throws InputError instead.
  install_mujoco_error_handlers();
  // leeway's InputError is bad input: ValueError, message unchanged. Other exceptions keep
  // pybind11's mapping (std::exception: RuntimeError, std::bad_alloc: MemoryError).
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });
  py::register_exception<NominalCollision>(m, "CollisionError", PyExc_RuntimeError);

  py::class_<Scene, std::shared_ptr<Scene>>(m, "Scene", "A loaded, recognised MJCF workcell.")
      .def_static(
          "load",
          [](const std::string& path, const std::string& tool) {
            SceneOptions o;
            o.tool_site = tool;
            return std::make_shared<Scene>(Scene::load(path, o));
          },
          py::arg("path"), py::arg("tool") = "tool0", py::call_guard<py::gil_scoped_release>(),
          "Loads an MJCF cell (or compiled .mjb). `tool` names the site at the robot's flange.\n"
          "Raises ValueError naming the file when it is missing or cannot be used.")
      .def_property_readonly("joint_names", &joint_names, "Robot joint names, in the order of every q.")
      .def_property_readonly("dof", &Scene::dof, "Number of robot joints.")
      .def_property_readonly("source", &Scene::source, "The file the cell was loaded from.")
      .def_property_readonly(
          "keyframes",
          [](const Scene& s) {
            py::dict out;
            for (const auto& k : s.keyframes()) out[py::str(k.name)] = k.q;
            return out;
          },
          "The cell's keyframes: name -> joint values [rad, m].")
      .def("__repr__", [](const Scene& s) {
        return "<leeway.Scene '" + s.source() + "', " + std::to_string(s.dof()) + " joints>";
      });

  m.def(
      "check",
      [](const std::shared_ptr<Scene>& scene, std::uint64_t seed, double goal_dz) {
        CheckOptions o;
        o.seed = seed;
        o.goal_dz = goal_dz;
        json j;
        {
          py::gil_scoped_release release;
          j = to_json(*scene, check_scene(*scene, o));
        }
        return to_python(j);
      },
      py::arg("scene"), py::arg("seed") = 1, py::arg("goal_dz") = 0.01,
      "Checks the cell as `leeway check --json` does: keyframe collisions and limits, goal obstacles,\n"
      "reach [m], overlaps [m]. Returns that JSON object as a dict (its 'problems' list is empty when\n"
      "the cell is clean). `goal_dz` is Algorithm 1's descent step [m]; `seed` seeds the IK restarts.");

  py::class_<BoundsStage>(m, "Stage", "The box of joint values at one point of the path.")
      .def_readonly("t", &BoundsStage::t, "Nominal time [s] (the path parameter on an untimed path).")
      .def_readonly("s", &BoundsStage::s, "Path parameter: waypoint index plus fraction of the segment.")
      .def_readonly("nominal", &BoundsStage::nominal, "Nominal configuration [rad, m].")
      .def_readonly("lower", &BoundsStage::lower, "Lower bound per joint [rad, m].")
      .def_readonly("upper", &BoundsStage::upper, "Upper bound per joint [rad, m].")
      .def("__repr__", [](const BoundsStage& b) {
        return "<leeway.Stage t=" + format_number(b.t) + " s, s=" + format_number(b.s) + ">";
      });

  py::class_<Bounds>(m, "Bounds",
                     "Bounds along a path: per waypoint a box [lower, upper] around the nominal q, linear\n"
                     "in the path parameter s between waypoints (docs/cli.md, 'Contract for a controller').")
      .def_property_readonly(
          "lower", [](const Bounds& b) { return waypoint_matrix(b, &WaypointBounds::lower); },
          "Lower bounds, N waypoints x n joints [rad, m] (float64).")
      .def_property_readonly(
          "upper", [](const Bounds& b) { return waypoint_matrix(b, &WaypointBounds::upper); },
          "Upper bounds, N x n [rad, m] (float64).")
      .def_property_readonly(
          "nominal", [](const Bounds& b) { return waypoint_matrix(b, &WaypointBounds::q); },
          "Nominal configurations, N x n [rad, m] (float64).")
      .def_property_readonly(
          "times",
          [](const Bounds& b) {
            const auto& t = b.trajectory->times();
            return py::array_t<double>(static_cast<py::ssize_t>(t.size()), t.data());
          },
          "Nominal time of each waypoint, N [s] (the path parameter on an untimed path).")
      .def_readonly("joint_names", &Bounds::joints, "Joint names, in column order.")
      .def_property_readonly(
          "duration", [](const Bounds& b) { return b.trajectory->duration(); }, "Nominal duration [s].")
      .def_property_readonly(
          "timed", [](const Bounds& b) { return b.trajectory->timed(); },
          "True when the times come from joint speeds; False when t = s.")
      .def_readonly("certified", &Bounds::certified,
                    "True when every box is proven collision-free (certified_region.proven), False when\n"
                    "not, None when the file does not say.")
      .def_property_readonly(
          "waypoint_count", [](const Bounds& b) { return b.trajectory->waypoint_count(); }, "N.")
      .def_property_readonly(
          "dof", [](const Bounds& b) { return b.trajectory->dof(); }, "n.")
      .def(
          "at_s", [](const Bounds& b, double s) { return b.trajectory->at_s(s); }, py::arg("s"),
          "The box at path parameter s (0 .. N-1; clamped outside). Raises ValueError on NaN.")
      .def(
          "at_t", [](const Bounds& b, double t) { return b.trajectory->at_t(t); }, py::arg("t"),
          "The box at nominal time t [s] (0 .. duration; clamped outside). Raises ValueError on NaN.")
      .def(
          "contains",
          [](const Bounds& b, double s, const Eigen::VectorXd& q) { return b.trajectory->contains(s, q); },
          py::arg("s"), py::arg("q"),
          "True when lower(s) <= q <= upper(s) in every joint (q in rad, m). ValueError on NaN s or a\n"
          "q of another size.")
      .def("sample", &sample_py, py::arg("dt"),
           "Rows every dt seconds of nominal time from 0 to the duration inclusive (the last row is the\n"
           "end): a dict of float64 arrays t [s], s (M) and nominal, lower, upper (M x n) [rad, m].\n"
           "Raises ValueError on dt <= 0, NaN, infinite, or more than 10,000,000 rows.")
      .def(
          "save",
          [](const Bounds& b, const std::string& path) {
            const std::string text = b.file.dump(2) + "\n";
            py::gil_scoped_release release;
            write_file_atomic(path, text);
          },
          py::arg("path"),
          "Writes the bounds file (JSON, leeway-bounds-2 for computed bounds) whole or not at all.")
      .def(
          "to_json", [](const Bounds& b) { return b.file.dump(2); },
          "The bounds file as JSON text (what save() writes).")
      .def("__len__", [](const Bounds& b) { return b.trajectory->waypoint_count(); })
      .def("__repr__", [](const Bounds& b) {
        return "<leeway.Bounds " + std::to_string(b.trajectory->waypoint_count()) + " waypoints x " +
               std::to_string(b.trajectory->dof()) + " joints, " + format_number(b.trajectory->duration()) +
               " s>";
      });

  m.def("bounds", &bounds_between, py::arg("scene"), py::arg("from_key"), py::arg("to_key"), py::kw_only(),
        py::arg("preset") = "leeway", py::arg("safety") = py::none(), py::arg("waypoints") = 2,
        py::arg("threads") = 0,
        "Bounds on the joint-linear path between two keyframes, as `leeway bounds --from --to`.\n"
        "preset: 'leeway' (tuned, certified) or 'thesis'; safety: 'certified', 'sampled', 'none' or\n"
        "None (the preset's: certified for 'leeway'); waypoints >= 2 along the straight path;\n"
        "threads: worker threads, 0 = one per hardware thread. Further keywords are parameters by\n"
        "their dotted names as in a parameter file, e.g. **{'height_map.max_cells': 3000}; an\n"
        "unknown name raises ValueError naming it. A colliding straight path raises CollisionError\n"
        "(the command line plans around it). Returns Bounds.");

  m.def(
      "read_bounds",
      [](const std::string& path, const std::shared_ptr<Scene>& scene) {
        return read_bounds_py(path, scene);
      },
      py::arg("path"), py::arg("scene") = py::none(),
      "Reads a bounds file. Without a scene it needs format 2 (its own times; joint limits not\n"
      "checked); with one, the file must match the cell (joints, limits) and a format-1 file is timed\n"
      "by the cell's joint speeds. Raises ValueError naming the file and the problem.");

  m.def("confidence_factor", &confidence_py, py::arg("scene"), py::arg("bounds"), py::kw_only(),
        py::arg("samples") = 10000, py::arg("windows") = 30, py::arg("seed") = 1, py::arg("threads") = 0,
        py::arg("self") = false,
        "Confidence Factor (thesis section 4.1) of the bounds against the cell's real obstacles:\n"
        "`samples` random configurations in each of `windows` windows of equal duration, seeded\n"
        "(deterministic for any thread count; threads 0 = one per hardware thread); self=True counts\n"
        "self-collisions too. Returns a dict: cf and ci95 (fractions, 1 = 100 %), samples,\n"
        "collisions, obstacle_collisions, self_collisions, any_collisions, counts, worst_window,\n"
        "worst_window_cf, window_cf, timed, duration [s, or segments when not timed].");
}
