#include "leeway/apps/tuning.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <limits>

#include "statistics.hpp"

#include "leeway/core/bounds.hpp"
#include "leeway/core/cell_defaults.hpp"
#include "leeway/core/confidence.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/path/nominal_path.hpp"

namespace leeway {
namespace {

using detail::median;
using detail::process_cpu_ms;

// The tuned volume parameters, in tuned_variables() order (log10_max_cells comes after alpha_ng).
struct VolumeField {
  const char* name;
  double VolumeParams::*field;
};
const VolumeField kVolumeFields[] = {
    {"d_t_lb", &VolumeParams::d_t_lb},     {"d_t_ub", &VolumeParams::d_t_ub},
    {"d_g_lb", &VolumeParams::d_g_lb},     {"d_g_ub", &VolumeParams::d_g_ub},
    {"d_ng_ub", &VolumeParams::d_ng_ub},   {"h_max", &VolumeParams::h_max},
    {"alpha_t", &VolumeParams::alpha_t},   {"alpha_g", &VolumeParams::alpha_g},
    {"alpha_ng", &VolumeParams::alpha_ng},
};
constexpr size_t kNumVolumeFields = sizeof(kVolumeFields) / sizeof(kVolumeFields[0]);
// Indices in the variable vector.
constexpr size_t kCellsIndex = kNumVolumeFields;
static_assert(kCellsIndex == kMaxCellsVariable, "kMaxCellsVariable must follow the volume fields");
constexpr size_t kMarginIndex = kNumVolumeFields + 1;
constexpr size_t kNumVariables = kNumVolumeFields + 2;

}  // namespace

std::string CaseSpec::label() const {
  return std::filesystem::path(cell).stem().string() + ":" + from + ":" + to;
}

CaseSpec parse_case(const std::string& text) {
  const auto second = text.rfind(':');
  const auto first =
      second == std::string::npos || second == 0 ? std::string::npos : text.rfind(':', second - 1);
  if (first == std::string::npos || first == 0 || second == first + 1 || second + 1 == text.size())
    throw InputError("tuning case '" + text +
                     "' must be CELL.xml:FROM:TO (a workcell file and two of its keyframes, e.g. "
                     "mjcf/workcells/dallara.xml:home:patch)");
  return {text.substr(0, first), text.substr(first + 1, second - first - 1), text.substr(second + 1)};
}

TuningCase::TuningCase(const CaseSpec& spec, const nlohmann::json& base_json, int waypoints,
                       int pool_capacity, const SceneOptions& options)
    : spec_(spec) {
  const std::string what = "tuning case '" + spec.cell + ":" + spec.from + ":" + spec.to + "'";
  try {
    if (!std::filesystem::is_regular_file(spec.cell)) throw InputError(spec.cell + ": no such file");
    scene_ = std::make_unique<Scene>(Scene::load(spec.cell, options));
    // The same nominal path as leeway bounds: checked, and planned around when it collides.
    PathRequest request;
    request.from = spec.from;
    request.to = spec.to;
    request.waypoints = waypoints;
    const NominalPath nominal = resolve_nominal_path(*scene_, request);
    if (!nominal.ok()) throw InputError(std::string(refusal_name(nominal.refusal)) + ": " + nominal.message);
    path_ = nominal.waypoints;  // within the limits: check_path tests them
    // leeway-tune tunes the guide, Algorithms 2 and 3 against the volume, as published: no safety
    // stage unless the base parameters ask for one.
    ParamLayers layers;
    layers.preset = "thesis";
    layers.object = base_json;
    layers.object_source = "the base parameters";
    params_ = compose_params(*scene_, layers);
    params_.validate();
    world_ = std::make_unique<VolumeModel>(*scene_, VolumeModel::capacity_for(*scene_, pool_capacity));
  } catch (const InputError& e) {
    throw InputError(what + ": " + e.what());
  }
}

std::vector<TunedVariable> tuned_variables() {
  // Bounds: docs/tuning.md, "Tuned variables". Lengths in metres. One variable per line:
  // clang-format off
  return {
      {"d_t_lb", 0.0, 1.5, 0.35, "m"},
      {"d_t_ub", 0.3, 3.0, 1.5, "m"},
      {"d_g_lb", 0.0, 1.0, 0.1, "m"},
      {"d_g_ub", 0.3, 3.0, 2.0, "m"},
      {"d_ng_ub", 0.05, 1.5, 0.5, "m"},
      {"h_max", 0.2, 3.0, 1.5, "m"},
      {"alpha_t", 0.25, 4.0, 1.0, "-"},
      {"alpha_g", 0.25, 4.0, 1.0, "-"},
      {"alpha_ng", 0.25, 4.0, 1.0, "-"},
      {"log10_max_cells", 2.0, 5.0, std::log10(20000.0), "log10 cells"},
      {"trail_margin", 0.0, 0.3, 0.0, "m"},
  };
  // clang-format on
}

int max_cells_from_log10(double x) { return static_cast<int>(std::lround(std::pow(10.0, x))); }

Params apply_variables(const Params& base, const std::vector<double>& x) {
  if (x.size() != kNumVariables)
    throw InputError("tuning: " + std::to_string(x.size()) + " variables given, " +
                     std::to_string(kNumVariables) + " expected");
  for (size_t i = 0; i < x.size(); ++i)
    if (!std::isfinite(x[i]))
      throw InputError("tuning: variable '" + tuned_variables()[i].name + "' is not finite");
  Params p = base;
  for (size_t i = 0; i < kNumVolumeFields; ++i) p.volume.*kVolumeFields[i].field = x[i];
  p.height_map.max_cells = max_cells_from_log10(x[kCellsIndex]);
  p.volume.trail_margin = x[kMarginIndex];
  return p;
}

std::vector<double> variables_of(const Params& p) {
  std::vector<double> x(kNumVariables);
  for (size_t i = 0; i < kNumVolumeFields; ++i) x[i] = p.volume.*kVolumeFields[i].field;
  x[kCellsIndex] = std::log10(static_cast<double>(p.height_map.max_cells));
  x[kMarginIndex] = p.volume.trail_margin;
  return x;
}

std::vector<double> bound_constraints(const std::vector<double>& x) {
  LEEWAY_DEMAND(x.size() == kNumVariables);
  return {x[0] - x[1] + kMinBoundGap, x[2] - x[3] + kMinBoundGap};
}

bool meets_bound_constraints(const std::vector<double>& x) {
  const auto c = bound_constraints(x);
  return std::all_of(c.begin(), c.end(), [](double v) { return v <= 0; });
}

double TimeModel::predict(long checks, long boxes, double near) const {
  const double c = static_cast<double>(checks);
  return ms_fixed + ms_per_check * c + ms_per_check_box * c * static_cast<double>(boxes) +
         ms_per_check_near * c * near;
}

TimeModel fit_time_model(const std::vector<TimingSample>& samples) {
  if (samples.size() < 2)
    throw InputError("time model: " + std::to_string(samples.size()) +
                     " timing sample(s), at least 2 needed");
  constexpr int kTerms = 4;
  const Eigen::Index n = static_cast<Eigen::Index>(samples.size());
  Eigen::MatrixXd a(n, kTerms);
  Eigen::VectorXd y(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& s = samples[static_cast<size_t>(i)];
    const double c = static_cast<double>(s.checks);
    a(i, 0) = 1;
    a(i, 1) = c;
    a(i, 2) = c * static_cast<double>(s.boxes);
    a(i, 3) = c * s.near;
    y[i] = s.ms;
  }
  // Relative errors: each row divided by its measured time, so that the many short runs of a search
  // weigh as much as the few long ones.
  Eigen::VectorXd w = Eigen::VectorXd::Ones(n);
  for (Eigen::Index i = 0; i < n; ++i)
    if (y[i] > 0) w[i] = 1 / y[i];
  const Eigen::MatrixXd aw = w.asDiagonal() * a;
  const Eigen::VectorXd yw = w.asDiagonal() * y;
  // Non-negative least squares: the best subset of terms whose plain fit is non-negative, with no
  // more terms than samples (2^4 - 1 subsets).
  Eigen::Matrix<double, kTerms, 1> best = Eigen::Matrix<double, kTerms, 1>::Zero();
  double best_sse = yw.squaredNorm();
  for (int mask = 1; mask < (1 << kTerms); ++mask) {
    std::vector<Eigen::Index> cols;
    for (Eigen::Index k = 0; k < kTerms; ++k)
      if (mask & (1 << k)) cols.push_back(k);
    if (static_cast<Eigen::Index>(cols.size()) > n) continue;
    Eigen::MatrixXd sub(n, static_cast<Eigen::Index>(cols.size()));
    for (size_t k = 0; k < cols.size(); ++k) sub.col(static_cast<Eigen::Index>(k)) = aw.col(cols[k]);
    // Scaled columns keep the solve well conditioned whatever the units.
    const Eigen::VectorXd scale = sub.colwise().norm().transpose();
    if ((scale.array() <= 0).any()) continue;
    const Eigen::MatrixXd scaled = sub * scale.cwiseInverse().asDiagonal();
    const auto qr = scaled.colPivHouseholderQr();
    if (qr.rank() < sub.cols()) continue;
    const Eigen::VectorXd coef = qr.solve(yw).cwiseQuotient(scale);
    if ((coef.array() < 0).any() || !coef.allFinite()) continue;
    const double sse = (sub * coef - yw).squaredNorm();
    if (sse < best_sse) {
      best_sse = sse;
      best.setZero();
      for (size_t k = 0; k < cols.size(); ++k) best[cols[k]] = coef[static_cast<Eigen::Index>(k)];
    }
  }
  TimeModel m;
  m.ms_fixed = best[0];
  m.ms_per_check = best[1];
  m.ms_per_check_box = best[2];
  m.ms_per_check_near = best[3];
  const Eigen::VectorXd fit = a * best;
  const double sst = (y.array() - y.mean()).square().sum();
  m.r2 = sst > 0 ? 1 - (fit - y).squaredNorm() / sst : 1.0;
  std::vector<double> rel;
  for (Eigen::Index i = 0; i < n; ++i)
    if (y[i] > 0) rel.push_back(std::abs(fit[i] - y[i]) / y[i]);
  m.median_rel_error = median(rel);
  m.samples = static_cast<int>(n);
  return m;
}

void width_stats(const Scene& scene, const BoundsParams& params, const std::vector<WaypointBounds>& bounds,
                 double min_width, CaseEval& e) {
  const auto kinds = bound_kinds(scene, params);
  e.bisected = 0;
  e.collapsed = 0;
  double width = 0, shortfall = 0;
  for (const auto& w : bounds)
    for (size_t i = 0; i < kinds.size(); ++i) {
      if (kinds[i] != BoundKind::kBisected) continue;
      const auto k = static_cast<Eigen::Index>(i);
      const double wi = w.upper[k] - w.lower[k];
      ++e.bisected;
      width += wi;
      if (w.collapsed[i]) {
        ++e.collapsed;
        shortfall += 1;
      } else if (min_width > 0) {
        shortfall += std::max(0.0, 1 - wi / min_width);
      }
    }
  e.mean_width = e.bisected > 0 ? width / e.bisected : 0;
  e.shortfall = e.bisected > 0 ? shortfall / e.bisected : 0;
}

void score_case(CaseEval& e, const Objective& objective) {
  const double ms = objective.time == Objective::Time::kWall  ? e.wall_ms
                    : objective.time == Objective::Time::kCpu ? e.cpu_ms
                                                              : e.cost_ms;
  const double seconds = ms / 1000;
  e.score = 100 * e.cf - objective.lambda * seconds - objective.mu * e.shortfall;
}

double aggregate_score(const std::vector<CaseEval>& evals, const Objective& objective) {
  LEEWAY_DEMAND(!evals.empty());
  if (objective.worst_case) {
    double worst = std::numeric_limits<double>::infinity();
    for (const auto& e : evals) worst = std::min(worst, e.score);
    return worst;
  }
  double sum = 0;
  for (const auto& e : evals) sum += e.score;
  return sum / static_cast<double>(evals.size());
}

double near_pairs(const Scene& scene, const std::vector<Eigen::VectorXd>& configs,
                  const std::vector<Box>& boxes) {
  if (configs.empty()) return 0;
  RobotState state(scene);
  const mjModel& m = scene.model();
  long pairs = 0;
  for (const auto& q : configs) {
    state.set(q);
    const mjData& d = state.data();
    for (int g : scene.link_geoms()) {
      const Eigen::Vector3d c(d.geom_xpos[3 * g], d.geom_xpos[3 * g + 1], d.geom_xpos[3 * g + 2]);
      const double r = m.geom_rbound[g];
      for (const auto& b : boxes) {
        const double reach = r + b.half_size.norm();
        if ((b.center - c).squaredNorm() <= reach * reach) ++pairs;
      }
    }
  }
  return static_cast<double>(pairs) / static_cast<double>(configs.size());
}

TimedRun timed_bounds(TuningCase& c, const Params& params, int repeats) {
  LEEWAY_DEMAND(repeats >= 1);
  std::vector<double> wall, cpu;
  TimedRun t;
  for (int r = 0; r < repeats; ++r) {
    const double c0 = process_cpu_ms();
    t.run = compute_bounds(c.scene(), c.world(), c.path(), params, 1);
    cpu.push_back(process_cpu_ms() - c0);
    wall.push_back(t.run.ms_total());
  }
  t.wall_ms = median(wall);
  t.cpu_ms = median(cpu);
  return t;
}

CaseEval evaluate_case(TuningCase& c, const Params& params, const CfParams& cf, int repeats, int cf_threads,
                       const TimeModel& model, const Objective& objective) {
  const TimedRun t = timed_bounds(c, params, repeats);
  const BoundsRun& run = t.run;
  CaseEval e;
  e.wall_ms = t.wall_ms;
  e.cpu_ms = t.cpu_ms;
  e.checks = run.checks;
  e.boxes = static_cast<long>(run.volume.boxes.size());
  e.cells = run.volume.cells_evaluated;
  e.near = near_pairs(c.scene(), c.path(), run.volume.boxes);
  e.cost_ms = model.predict(e.checks, e.boxes, e.near);
  width_stats(c.scene(), params.bounds, run.bounds, objective.min_width, e);
  const CfResult r = confidence_factor(c.scene(), run.bounds, cf, cf_threads);
  e.cf = r.cf;
  e.ci_low = r.ci_low;
  e.ci_high = r.ci_high;
  score_case(e, objective);
  return e;
}

nlohmann::json tuned_params_json(const nlohmann::json& base_json, const Params& p) {
  nlohmann::json j = base_json.is_object() ? base_json : nlohmann::json::object();
  j["height_map"]["max_cells"] = p.height_map.max_cells;
  for (const auto& f : kVolumeFields) j["volume"][f.name] = p.volume.*f.field;
  j["volume"]["trail_margin"] = p.volume.trail_margin;
  return j;
}

}  // namespace leeway
