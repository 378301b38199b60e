#include "leeway/core/scene.hpp"

#include <cmath>
#include <cstdlib>
#include <sstream>

#include "leeway/core/error.hpp"
#include "leeway/core/numbers.hpp"

namespace leeway {
namespace {

int top_ancestor(const mjModel& m, int body) {
  while (body > 0 && m.body_parentid[body] != 0) body = m.body_parentid[body];
  return body;
}

const char* joint_type_name(int type) {
  switch (type) {
    case mjJNT_FREE:
      return "free";
    case mjJNT_BALL:
      return "ball";
    case mjJNT_SLIDE:
      return "slide";
    default:
      return "hinge";
  }
}

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + ("'" + s + "'");
  return out.empty() ? "(none)" : out;
}

// Robot joint j, checked: a named hinge or slide with a finite, non-empty range of workcell scale,
// a finite axis and anchor, and a valid max speed (user[0]); all in the subtree of `robot_root`
// (set by the first joint, -1 before it).
RobotJoint robot_joint(const mjModel& m, int j, const std::string& file, int& robot_root) {
  const std::string name = object_name(m, mjOBJ_JOINT, j);
  const std::string label = name.empty() ? "#" + std::to_string(j) : "'" + name + "'";
  if (m.jnt_type[j] != mjJNT_HINGE && m.jnt_type[j] != mjJNT_SLIDE)
    throw InputError(file + ": joint " + label + " is a " + joint_type_name(m.jnt_type[j]) +
                     " joint; robot joints must be hinge or slide");
  if (name.empty())
    throw InputError(file + ": joint #" + std::to_string(j) + " has no name; name every robot joint");
  const int root = top_ancestor(m, m.jnt_bodyid[j]);
  if (robot_root < 0) {
    robot_root = root;
  } else if (root != robot_root) {
    throw InputError(file + ": joint " + label + " is in body '" + object_name(m, mjOBJ_BODY, root) +
                     "', outside the robot subtree '" + object_name(m, mjOBJ_BODY, robot_root) +
                     "'; leeway supports one robot (one top-level body with joints)");
  }
  if (!m.jnt_limited[j])
    throw InputError(file + ": joint " + label + " has no range; robot joints need limits");
  RobotJoint rj;
  rj.name = name;
  rj.id = j;
  rj.prismatic = m.jnt_type[j] == mjJNT_SLIDE;
  rj.lower = m.jnt_range[2 * j];
  rj.upper = m.jnt_range[2 * j + 1];
  const char* unit = rj.prismatic ? " m" : " rad";
  if (!std::isfinite(rj.lower) || !std::isfinite(rj.upper))
    throw InputError(file + ": joint " + label + " range '" + format_number(rj.lower) + " " +
                     format_number(rj.upper) + "' is not finite");
  if (rj.lower >= rj.upper)
    throw InputError(file + ": joint " + label + " range '" + format_number(rj.lower) + " " +
                     format_number(rj.upper) + "' is empty");
  if (std::abs(rj.lower) > kMaxLength || std::abs(rj.upper) > kMaxLength)
    throw InputError(file + ": joint " + label + " range '" + format_number(rj.lower) + " " +
                     format_number(rj.upper) + "'" + unit + " goes beyond +-" + format_number(kMaxLength) +
                     unit + " (after MuJoCo's unit conversion); no robot joint moves that far");
  // MuJoCo compiles a NaN or inf joint axis or anchor (it normalises the axis without checking):
  // the links' poses are then NaN at every value but the reference, and the midphase's cell
  // index of a NaN coordinate is undefined behaviour (found by fuzzing; fuzz/regressions/cell/).
  auto require_finite = [&](const char* what, const mjtNum* v) {
    if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]))
      throw InputError(file + ": joint " + label + " " + what + " '" + format_number(v[0]) + " " +
                       format_number(v[1]) + " " + format_number(v[2]) + "' is not finite");
  };
  require_finite("axis", m.jnt_axis + 3 * j);
  require_finite("pos", m.jnt_pos + 3 * j);
  if (m.nuser_jnt > 0) {
    rj.max_speed = m.jnt_user[j * m.nuser_jnt];
    if (!std::isfinite(rj.max_speed) || rj.max_speed < 0)
      throw InputError(file + ": joint " + label + " user[0] (max speed) '" + format_number(rj.max_speed) +
                       "' must be a finite value >= 0");
  }
  return rj;
}

// Refuses values of an element that are not finite or beyond +-limit: MuJoCo compiles NaN and inf,
// and the collision checks would then answer nonsense.
void refuse_values(const std::string& file, const std::string& element, const char* what, const mjtNum* v,
                   int n, double limit, const char* unit) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(v[i]) || std::abs(v[i]) > limit) {
      std::string values;
      for (int k = 0; k < n; ++k) values += (k ? " " : "") + format_number(v[k]);
      throw InputError(file + ": " + element + " " + what + " '" + values + "'" + unit +
                       (std::isfinite(v[i]) ? " goes beyond +-" + format_number(limit) + unit
                                            : std::string(" is not finite")));
    }
}

// Keyframe k, its qpos checked finite (joint j's value is qpos entry j).
Keyframe keyframe_of(const mjModel& m, int k, const std::string& file,
                     const std::vector<RobotJoint>& joints) {
  Keyframe kf;
  kf.name = object_name(m, mjOBJ_KEY, k);
  if (kf.name.empty()) kf.name = "#" + std::to_string(k);
  kf.q = Eigen::Map<const Eigen::VectorXd>(m.key_qpos + k * m.nq, m.nq);
  for (int i = 0; i < m.nq; ++i)
    if (!std::isfinite(kf.q[i]))
      throw InputError(file + ": keyframe '" + kf.name + "' qpos value " + std::to_string(i + 1) +
                       " (joint '" + joints[static_cast<size_t>(i)].name + "') is '" +
                       format_number(kf.q[i]) + "', not a finite number");
  return kf;
}

}  // namespace

Eigen::VectorXd parse_vector(const std::string& text, const std::string& what) {
  std::vector<double> values;
  std::string token;
  std::vector<std::string> tokens;
  // Commas separate values as spaces do, but an empty field between commas ("1,,2", a leading or
  // trailing comma) is a mistake, not a value to skip.
  bool field_has_value = false, comma = false;
  auto empty_field = [&] { return InputError(what + ": '" + text + "' has an empty value between commas"); };
  for (char c : text) {
    const bool space = std::isspace(static_cast<unsigned char>(c));
    if (c == ',' || space) {
      if (!token.empty()) {
        tokens.push_back(token);
        field_has_value = true;
      }
      token.clear();
      if (c == ',') {
        if (!field_has_value) throw empty_field();
        field_has_value = false;
        comma = true;
      }
    } else {
      token += c;
    }
  }
  if (!token.empty()) {
    tokens.push_back(token);
    field_has_value = true;
  }
  if (comma && !field_has_value) throw empty_field();
  for (size_t i = 0; i < tokens.size(); ++i) {
    const std::string& t = tokens[i];
    char* end = nullptr;
    const double v = std::strtod(t.c_str(), &end);
    if (end == t.c_str() || *end != '\0')
      throw InputError(what + ": value " + std::to_string(i + 1) + " '" + t + "' is not a number");
    if (!std::isfinite(v))
      throw InputError(what + ": value " + std::to_string(i + 1) + " '" + t + "' is not finite");
    values.push_back(v);
  }
  return Eigen::Map<Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
}

Scene Scene::load(const std::string& path, const SceneOptions& options) {
  return from_model(load_model_file(path), path, options);
}

Scene Scene::from_model(ModelPtr model, std::string source, const SceneOptions& options) {
  LEEWAY_DEMAND(model != nullptr);
  Scene s;
  s.model_ = std::move(model);
  s.source_ = std::move(source);
  s.recognise(options);
  return s;
}

void Scene::recognise(const SceneOptions& options) {
  mjModel& m = *model_;
  const std::string& file = source_;

  // Robot joints: every joint of the model, all in one top-level body subtree.
  if (m.njnt == 0)
    throw InputError(file +
                     ": no robot joints: the model has no hinge or slide joint "
                     "(see docs/mjcf-conventions.md)");
  for (int j = 0; j < m.njnt; ++j) joints_.push_back(robot_joint(m, j, file, robot_root_));
  LEEWAY_DEMAND(m.nq == m.njnt);

  // What moves with the joints. MuJoCo numbers bodies parents first, so one pass suffices.
  std::vector<bool> moving(static_cast<size_t>(m.nbody), false);
  for (int b = 1; b < m.nbody; ++b) {
    moving[static_cast<size_t>(b)] = m.body_jntnum[b] > 0 || moving[static_cast<size_t>(m.body_parentid[b])];
    if (moving[static_cast<size_t>(b)]) moving_bodies_.push_back(b);
  }
  for (int g = 0; g < m.ngeom; ++g)
    if (moving[static_cast<size_t>(m.geom_bodyid[g])]) moving_geoms_.push_back(g);
  for (int s = 0; s < m.nsite; ++s)
    if (moving[static_cast<size_t>(m.site_bodyid[s])]) moving_sites_.push_back(s);

  // Geoms: links, robot base, obstacles; bitmasks normalised for robot-versus-obstacle contacts.
  roles_.assign(static_cast<size_t>(m.ngeom), GeomRole::kIgnored);
  for (int g = 0; g < m.ngeom; ++g) {
    const bool collidable = m.geom_contype[g] != 0 || m.geom_conaffinity[g] != 0;
    const int body = m.geom_bodyid[g];
    const bool robot = body != 0 && top_ancestor(m, body) == robot_root_;
    GeomRole r = GeomRole::kIgnored;
    if (collidable) {
      if (robot)
        r = m.body_weldid[body] != 0 ? GeomRole::kLink : GeomRole::kRobotBase;
      else
        r = GeomRole::kObstacle;
    }
    roles_[static_cast<size_t>(g)] = r;
    switch (r) {
      case GeomRole::kLink:
        link_geoms_.push_back(g);
        m.geom_contype[g] = 1;
        m.geom_conaffinity[g] = 0;
        break;
      case GeomRole::kObstacle:
        obstacle_geoms_.push_back(g);
        m.geom_contype[g] = 0;
        m.geom_conaffinity[g] = 1;
        break;
      case GeomRole::kRobotBase:
        base_geoms_.push_back(g);
        [[fallthrough]];
      case GeomRole::kIgnored:
        m.geom_contype[g] = 0;
        m.geom_conaffinity[g] = 0;
        break;
    }
  }
  if (link_geoms_.empty())
    throw InputError(file +
                     ": the robot has no collidable geoms on its moving bodies "
                     "(contype or conaffinity must be non-zero)");

  find_self_pairs();
  override_blinding_options(m);

  // Sites: the tool site in the robot, goal sites outside it.
  // A model the midphase cannot answer for (explicit pairs, excludes, ...) is checked by MuJoCo's
  // full pass: decided once here, not on every check.
  checker_ = emulates_mj_collision(m) ? options.checker : CollisionChecker::kMujoco;
  tool_site_ = mj_name2id(&m, mjOBJ_SITE, options.tool_site.c_str());
  if (tool_site_ < 0)
    throw InputError(file + ": no site named '" + options.tool_site +
                     "' for the robot's tool (SceneOptions::tool_site)");
  const int tool_body = m.site_bodyid[tool_site_];
  if (tool_body == 0 || top_ancestor(m, tool_body) != robot_root_ || m.body_weldid[tool_body] == 0)
    throw InputError(file + ": tool site '" + options.tool_site + "' is not on a moving body of the robot");
  for (int i = 0; i < m.nsite; ++i) {
    const int b = m.site_bodyid[i];
    if (b == 0 || top_ancestor(m, b) != robot_root_) goal_sites_.push_back(i);
  }

  // Keyframes.
  for (int k = 0; k < m.nkey; ++k) keyframes_.push_back(keyframe_of(m, k, file, joints_));

  // The static side of every robot-versus-obstacle check: every geom that is not a link, at its
  // pose at qpos0 (none of them moves with the robot's joints), indexed for the midphase.
  DataPtr d = make_data(m);
  mj_kinematics(&m, d.get());
  // Every collidable geom's size and pose must be finite numbers of workcell scale: MuJoCo compiles
  // NaN and inf, and the collision checks would then answer nonsense.
  for (int g = 0; g < m.ngeom; ++g) {
    if (roles_[static_cast<size_t>(g)] == GeomRole::kIgnored) continue;
    auto refuse = [&](const char* what, const mjtNum* v, int n, double limit, const char* unit) {
      refuse_values(file, "geom '" + geom_label(g) + "'", what, v, n, limit, unit);
    };
    refuse("size", m.geom_size + 3 * g, 3, kMaxLength, " m");
    refuse("pos", m.geom_pos + 3 * g, 3, kMaxLength, " m");
    refuse("quat", m.geom_quat + 4 * g, 4, 2.0, "");
    refuse("world position", d->geom_xpos + 3 * g, 3, kMaxLength, " m");
    refuse("world orientation", d->geom_xmat + 9 * g, 9, 2.0, "");
    // The contact margin and gap widen every collision query: a NaN made the midphase's cell index
    // undefined behaviour, an inf one made every geom touch (found by fuzzing; fuzz/regressions/cell/).
    refuse("margin", m.geom_margin + g, 1, kMaxLength, " m");
    refuse("gap", m.geom_gap + g, 1, kMaxLength, " m");
  }
  // The tool site and the goal sites likewise: a NaN site gave NaN tool poses and goals.
  std::vector<int> sites = goal_sites_;
  sites.push_back(tool_site_);
  for (int i : sites) {
    const std::string element = "site '" + object_name(m, mjOBJ_SITE, i) + "'";
    refuse_values(file, element, "pos", m.site_pos + 3 * i, 3, kMaxLength, " m");
    refuse_values(file, element, "quat", m.site_quat + 4 * i, 4, 2.0, "");
    refuse_values(file, element, "world position", d->site_xpos + 3 * i, 3, kMaxLength, " m");
    refuse_values(file, element, "world orientation", d->site_xmat + 9 * i, 9, 2.0, "");
  }
  std::vector<int> statics;
  for (int g = 0; g < m.ngeom; ++g)
    if (roles_[static_cast<size_t>(g)] != GeomRole::kLink) statics.push_back(g);
  statics_.build(m, *d, statics);
}

// A cell's <option> can switch MuJoCo's contacts off or shift them, and then every check would call
// a colliding configuration free. leeway's checks are the geoms' own contacts with their own
// margins, so those settings are reset in the scene's model, each said in overridden_options().
void Scene::override_blinding_options(mjModel& m) {
  if (m.opt.disableflags & mjDSBL_CONTACT)
    overridden_options_.push_back("<flag contact=\"disable\"/>: leeway checks contacts anyway");
  if (m.opt.disableflags & mjDSBL_CONSTRAINT)
    overridden_options_.push_back("<flag constraint=\"disable\"/>: leeway checks contacts anyway");
  if (m.opt.enableflags & mjENBL_OVERRIDE)
    overridden_options_.push_back("<flag override=\"enable\"/> (o_margin " + format_number(m.opt.o_margin) +
                                  " m): leeway uses each geom's own margin");
  if (m.opt.collision != mjCOL_ALL)
    overridden_options_.push_back(std::string("collision=\"") +
                                  (m.opt.collision == mjCOL_PAIR ? "predefined" : "dynamic") +
                                  "\": leeway checks every pair of geoms its rules make collidable");
  m.opt.disableflags &= ~(mjDSBL_CONTACT | mjDSBL_CONSTRAINT);
  m.opt.enableflags &= ~mjENBL_OVERRIDE;
  m.opt.collision = mjCOL_ALL;
}

void Scene::find_self_pairs() {
  const mjModel& m = *model_;
  const std::string& file = source_;
  auto robot_body = [&](int b) { return b > 0 && top_ancestor(m, b) == robot_root_; };
  auto body_label = [&](int b) {
    const std::string n = object_name(m, mjOBJ_BODY, b);
    return n.empty() ? (b == 0 ? std::string("world") : "#" + std::to_string(b)) : n;
  };
  // MuJoCo's body excludes: between robot bodies they drop self pairs; between the robot and the
  // cell they would drop obstacle contacts, which leeway refuses (a bound must never ignore the cell).
  std::vector<std::pair<int, int>> body_excludes;
  for (int i = 0; i < m.nexclude; ++i) {
    const auto [b1, b2] = excluded_bodies(m, i);
    if (robot_body(b1) != robot_body(b2))
      throw InputError(file + ": <exclude body1='" + body_label(b1) + "' body2='" + body_label(b2) +
                       "'> pairs a robot body with a body of the cell; leeway excludes only robot-robot "
                       "pairs (docs/mjcf-conventions.md)");
    if (robot_body(b1)) body_excludes.emplace_back(b1, b2);
  }
  auto body_excluded = [&](int b1, int b2) {
    for (const auto& [x, y] : body_excludes)
      if ((x == b1 && y == b2) || (x == b2 && y == b1)) return true;
    return false;
  };
  // Geom excludes: custom texts named leeway_exclude* whose data names two robot geoms.
  std::vector<std::pair<int, int>> geom_excludes;
  for (int t = 0; t < m.ntext; ++t) {
    const std::string name = object_name(m, mjOBJ_TEXT, t);
    if (name.rfind("leeway_exclude", 0) != 0) continue;
    std::istringstream words(
        std::string(m.text_data + m.text_adr[t], static_cast<size_t>(std::max(0, m.text_size[t] - 1))));
    std::vector<std::string> geoms;
    for (std::string w; words >> w;) geoms.push_back(w);
    if (geoms.size() != 2)
      throw InputError(file + ": custom text '" + name + "' must name two robot geoms, not " +
                       std::to_string(geoms.size()) + " words");
    int ids[2];
    for (int k = 0; k < 2; ++k) {
      ids[k] = mj_name2id(&m, mjOBJ_GEOM, geoms[static_cast<size_t>(k)].c_str());
      if (ids[k] < 0)
        throw InputError(file + ": custom text '" + name + "' names geom '" + geoms[static_cast<size_t>(k)] +
                         "', which does not exist");
      const GeomRole r = roles_[static_cast<size_t>(ids[k])];
      if (r != GeomRole::kLink && r != GeomRole::kRobotBase)
        throw InputError(file + ": custom text '" + name + "' names geom '" + geoms[static_cast<size_t>(k)] +
                         "', which is not a collidable robot geom");
    }
    geom_excludes.emplace_back(ids[0], ids[1]);
  }
  auto geom_excluded = [&](int g1, int g2) {
    for (const auto& [x, y] : geom_excludes)
      if ((x == g1 && y == g2) || (x == g2 && y == g1)) return true;
    return false;
  };

  std::vector<int> robot;
  for (int g = 0; g < m.ngeom; ++g)
    if (roles_[static_cast<size_t>(g)] == GeomRole::kLink ||
        roles_[static_cast<size_t>(g)] == GeomRole::kRobotBase)
      robot.push_back(g);
  auto part = [&](int g) { return m.body_weldid[m.geom_bodyid[g]]; };
  auto parent_part = [&](int w) { return w == 0 ? -1 : m.body_weldid[m.body_parentid[w]]; };
  for (size_t i = 0; i < robot.size(); ++i)
    for (size_t j = i + 1; j < robot.size(); ++j) {
      int g1 = robot[i], g2 = robot[j];
      int w1 = part(g1), w2 = part(g2);
      if (w1 == w2 || parent_part(w1) == w2 || parent_part(w2) == w1) continue;  // rigid or jointed together
      if (w1 > w2) {
        std::swap(g1, g2);
        std::swap(w1, w2);
      }
      const bool by_body = body_excluded(m.geom_bodyid[g1], m.geom_bodyid[g2]);
      if (by_body || geom_excluded(g1, g2))
        excluded_pairs_.push_back({g1, g2, by_body});
      else
        self_pairs_.push_back({g1, g2});
    }
}

std::vector<std::string> Scene::joint_names() const {
  std::vector<std::string> out;
  for (const auto& j : joints_) out.push_back(j.name);
  return out;
}

Eigen::VectorXd Scene::lower_limits() const {
  Eigen::VectorXd v(dof());
  for (int i = 0; i < dof(); ++i) v[i] = joints_[static_cast<size_t>(i)].lower;
  return v;
}

Eigen::VectorXd Scene::upper_limits() const {
  Eigen::VectorXd v(dof());
  for (int i = 0; i < dof(); ++i) v[i] = joints_[static_cast<size_t>(i)].upper;
  return v;
}

std::string Scene::geom_label(int geom) const {
  const std::string n = object_name(*model_, mjOBJ_GEOM, geom);
  if (!n.empty()) return n;
  const std::string body = object_name(*model_, mjOBJ_BODY, model_->geom_bodyid[geom]);
  return "unnamed geom #" + std::to_string(geom) + " on body '" + (body.empty() ? "world" : body) + "'";
}

int Scene::goal_site(const std::string& name) const {
  std::vector<std::string> names;
  for (int s : goal_sites_) {
    const std::string n = object_name(*model_, mjOBJ_SITE, s);
    if (n == name) return s;
    names.push_back(n);
  }
  throw InputError(source_ + ": no goal site '" + name + "'; goal sites: " + join(names));
}

const Keyframe& Scene::keyframe(const std::string& name) const {
  std::vector<std::string> names;
  for (const auto& k : keyframes_) {
    if (k.name == name) return k;
    names.push_back(k.name);
  }
  throw InputError(source_ + ": no keyframe '" + name + "'; keyframes: " + join(names));
}

void Scene::validate_configuration(const Eigen::VectorXd& q, const std::string& what) const {
  if (q.size() != dof())
    throw InputError(what + ": " + std::to_string(q.size()) + " values given, the robot in " + source_ +
                     " has " + std::to_string(dof()) + " joints");
  for (int i = 0; i < dof(); ++i)
    if (!std::isfinite(q[i]))
      throw InputError(what + ": joint '" + joints_[static_cast<size_t>(i)].name + "' value '" +
                       format_number(q[i]) + "' is not finite");
}

std::vector<int> Scene::joints_outside_limits(const Eigen::VectorXd& q) const {
  std::vector<int> out;
  for (int i = 0; i < dof(); ++i) {
    const auto& j = joints_[static_cast<size_t>(i)];
    if (q[i] < j.lower || q[i] > j.upper) out.push_back(i);
  }
  return out;
}

void Scene::set_qpos(mjData& d, const Eigen::VectorXd& q) const {
  for (int i = 0; i < dof(); ++i) d.qpos[model_->jnt_qposadr[joints_[static_cast<size_t>(i)].id]] = q[i];
}

}  // namespace leeway
