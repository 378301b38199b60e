#pragma once
//! @file bounds_export.hpp
//! The bounds in the forms a controller takes: stages every dt (CSV, JSON, NumPy .npz) for shooting
//! nodes (acados' lbx/ubx, a time-dependent box in OCS2), and Drake HPolyhedron boxes in the
//! IrisRegions YAML layout (docs/cli.md, `leeway sample`).

#include <string>
#include <vector>

#include "leeway/core/bounds_trajectory.hpp"

namespace leeway {

//! The file kinds `leeway sample` writes.
enum class StagesFormat { kCsv, kJson, kNpz, kDrakeYaml };

//! The format a file name's ending asks for: .csv, .json, .npz, .yaml or .yml (drake-yaml).
//! @throws InputError on any other ending.
StagesFormat stages_format_of(const std::string& path);

//! Writes the stages of `trajectory` every `dt` seconds (BoundsTrajectory::sample) to `path`, whole
//! or not at all (a temporary file renamed over it). `joints` names the columns; `source` (the
//! bounds file) goes into the header. CSV: a leading `#` line with the units, then the columns t, s
//! and per joint nominal_J, lower_J, upper_J. JSON: format "leeway-stages-1" with the same per
//! stage. NPZ: arrays t and s (M), nominal, lower and upper (M x n), joints (n names).
//! @throws InputError on a bad dt (BoundsTrajectory::sample_count), an .npz over 4 GiB, joint names
//! that do not match the trajectory, or a failed write.
void write_stages(const BoundsTrajectory& trajectory, const std::vector<std::string>& joints, double dt,
                  StagesFormat format, const std::string& path, const std::string& source);

//! Drake's IrisRegions YAML (geometry::optimization::LoadIrisRegionsYamlFile): per waypoint i a
//! region `waypoint_III`, the HPolyhedron {q : A q <= b} with A = [I; -I] and b = [upper; -lower].
//! With `segments`, also per segment i a region `segment_III` in dimension n + 1 over (q, f), f the
//! fraction of the segment in [0, 1]: exactly the set the bounds allow there, lower(f) <= q <=
//! upper(f) with lower and upper linear in f (convex, so no hull is needed and nothing is added).
std::string drake_yaml(const BoundsTrajectory& trajectory, const std::vector<std::string>& joints,
                       bool segments, const std::string& source);

}  // namespace leeway
