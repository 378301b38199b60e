#include "leeway/core/cell_defaults.hpp"

#include <cmath>

#include "leeway/core/error.hpp"

namespace leeway {

void apply_cell_defaults(const Scene& scene, Params& params) {
  const mjModel& m = scene.model();
  auto numeric = [&](const char* name, double& out) {
    const int id = mj_name2id(&m, mjOBJ_NUMERIC, name);
    if (id < 0) return false;
    // Exactly one value: a second ("2 500") is a typo or a misunderstanding, not something to ignore.
    if (m.numeric_size[id] != 1 || !std::isfinite(m.numeric_data[m.numeric_adr[id]]))
      throw InputError(scene.source() + ": custom numeric '" + name +
                       "' must hold one finite number (it holds " + std::to_string(m.numeric_size[id]) + ")");
    out = m.numeric_data[m.numeric_adr[id]];
    return true;
  };
  double v = 0;
  if (numeric("leeway_reach_radius", v)) {
    if (!(v >= kMinMapSide && v <= kMaxLength))
      throw InputError(scene.source() + ": custom numeric 'leeway_reach_radius' = " + format_number(v) +
                       " m must be between " + format_number(kMinMapSide) + " and " +
                       format_number(kMaxLength) + " m");
    params.volume.reach_radius = v;
  }
  if (numeric("leeway_add_obstacle_boxes", v)) {
    if (v != 0 && v != 1)
      throw InputError(scene.source() + ": custom numeric 'leeway_add_obstacle_boxes' = " + format_number(v) +
                       " must be 0 or 1");
    params.volume.add_obstacle_boxes = v == 1;
  }
}

Params compose_params(const Scene& scene, const ParamLayers& layers) {
  Params p = preset_params(layers.preset);
  apply_cell_defaults(scene, p);
  if (!layers.file.empty()) p = read_params(layers.file, p);
  if (!layers.object.is_null()) p = params_from_json(layers.object, layers.object_source, p);
  if (layers.safety) p.safety.mode = *layers.safety;
  return p;
}

}  // namespace leeway
