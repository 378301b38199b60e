#include "leeway/core/collision.hpp"

#include <cmath>
#include <limits>

#include "leeway/core/error.hpp"

namespace leeway {
namespace {

// mj_collideGeoms's built-in filter (MuJoCo 2.2.2, engine_collision_driver.c, mj_contactFilter):
// true when the pair is discarded.
bool filtered(const mjModel& m, int g1, int g2) {
  if (!(m.geom_contype[g1] & m.geom_conaffinity[g2]) && !(m.geom_contype[g2] & m.geom_conaffinity[g1]))
    return true;
  const int weld1 = m.body_weldid[m.geom_bodyid[g1]], weld2 = m.body_weldid[m.geom_bodyid[g2]];
  if (weld1 == weld2) return true;
  const bool filter_parent = !(m.opt.disableflags & mjDSBL_FILTERPARENT) && weld1 && weld2;
  const int parent1 = m.body_weldid[m.body_parentid[weld1]], parent2 = m.body_weldid[m.body_parentid[weld2]];
  return filter_parent && (weld1 == parent2 || weld2 == parent1);
}

double plane_distance(const mjData& d, int plane, int geom) {
  const mjtNum* mat = d.geom_xmat + 9 * plane;
  const mjtNum* p = d.geom_xpos + 3 * plane;
  const mjtNum* x = d.geom_xpos + 3 * geom;
  return (x[0] - p[0]) * mat[2] + (x[1] - p[1]) * mat[5] + (x[2] - p[2]) * mat[8];
}

}  // namespace

// mj_collideGeoms up to the narrowphase's contact count, without adding contacts.
bool geoms_in_contact(const mjModel& m, const mjData& d, int g1, int g2) {
  return !filtered(m, g1, g2) && geoms_touch(m, d, g1, g2);
}

// mj_collideGeoms after its filter: margin, bounding spheres, planes, then the narrowphase.
bool geoms_touch(const mjModel& m, const mjData& d, int g1, int g2) {
  if (m.geom_type[g1] > m.geom_type[g2]) std::swap(g1, g2);
  const mjfCollision collide = mjCOLLISIONFUNC[m.geom_type[g1]][m.geom_type[g2]];
  if (!collide) return false;
  const mjtNum margin = std::max(m.geom_margin[g1], m.geom_margin[g2]);
  const mjtNum* x1 = d.geom_xpos + 3 * g1;
  const mjtNum* x2 = d.geom_xpos + 3 * g2;
  const mjtNum r1 = m.geom_rbound[g1], r2 = m.geom_rbound[g2];
  if (r1 > 0 && r2 > 0) {
    const mjtNum dx = x1[0] - x2[0], dy = x1[1] - x2[1], dz = x1[2] - x2[2];
    if (std::sqrt(dx * dx + dy * dy + dz * dz) > r1 + r2 + margin) return false;
  }
  if (m.geom_type[g1] == mjGEOM_PLANE && r2 > 0 && plane_distance(d, g1, g2) > margin + r2) return false;
  if (m.geom_type[g2] == mjGEOM_PLANE && r1 > 0 && plane_distance(d, g2, g1) > margin + r1) return false;
  mjContact con[mjMAXCONPAIR];
  return collide(&m, &d, con, g1, g2, margin) > 0;
}

const char* checker_name(CollisionChecker c) {
  return c == CollisionChecker::kMujoco ? "mujoco" : "midphase";
}

CollisionChecker parse_checker(const std::string& name) {
  if (name == "midphase") return CollisionChecker::kMidphase;
  if (name == "mujoco") return CollisionChecker::kMujoco;
  throw InputError("collision checker '" + name + "' is not one of: midphase, mujoco");
}

bool emulates_mj_collision(const mjModel& m) {
  return m.npair == 0 && !excludes_a_contact(m) && !(m.opt.enableflags & mjENBL_OVERRIDE) &&
         !(m.opt.disableflags & (mjDSBL_CONTACT | mjDSBL_CONSTRAINT)) && m.nconmax != 0 &&
         !mjcb_contactfilter;
}

std::pair<int, int> excluded_bodies(const mjModel& m, int i) {
  // MuJoCo 2.2.2 stores ((body1 + 1) << 16) + body2 + 1, sorted, with body1 < body2.
  const int sig = m.exclude_signature[i];
  return {(sig >> 16) - 1, (sig & 0xFFFF) - 1};
}

bool excludes_a_contact(const mjModel& m) {
  for (int i = 0; i < m.nexclude; ++i) {
    const auto [b1, b2] = excluded_bodies(m, i);
    for (int g1 = m.body_geomadr[b1]; g1 >= 0 && g1 < m.body_geomadr[b1] + m.body_geomnum[b1]; ++g1)
      for (int g2 = m.body_geomadr[b2]; g2 >= 0 && g2 < m.body_geomadr[b2] + m.body_geomnum[b2]; ++g2)
        if ((m.geom_contype[g1] & m.geom_conaffinity[g2]) || (m.geom_contype[g2] & m.geom_conaffinity[g1]))
          return true;
  }
  return false;
}

Aabb geom_aabb(const mjModel& m, const mjData& d, int g) {
  const Eigen::Map<const Eigen::Vector3d> x(d.geom_xpos + 3 * g);
  Aabb a;
  if (m.geom_type[g] == mjGEOM_BOX) {
    const Eigen::Map<const Eigen::Matrix<mjtNum, 3, 3, Eigen::RowMajor>> r(d.geom_xmat + 9 * g);
    const Eigen::Map<const Eigen::Vector3d> h(m.geom_size + 3 * g);
    const Eigen::Vector3d e = r.cwiseAbs() * h;
    a.lo = x - e;
    a.hi = x + e;
  } else if (m.geom_type[g] != mjGEOM_PLANE && m.geom_rbound[g] > 0) {
    a.lo = x.array() - m.geom_rbound[g];
    a.hi = x.array() + m.geom_rbound[g];
  } else {
    a.lo.setConstant(-std::numeric_limits<double>::infinity());
    a.hi.setConstant(std::numeric_limits<double>::infinity());
  }
  return a;
}

void StaticGeoms::build(const mjModel& m, const mjData& d, const std::vector<int>& candidates) {
  geoms.clear();
  max_margin = 0;
  std::vector<Aabb> boxes;
  for (int g : candidates) {
    if (m.geom_contype[g] == 0 && m.geom_conaffinity[g] == 0) continue;
    geoms.push_back(g);
    boxes.push_back(geom_aabb(m, d, g));
    max_margin = std::max(max_margin, static_cast<double>(m.geom_margin[g]));
  }
  grid.build(boxes);
}

bool any_contact(const mjModel& m, const mjData& d, const std::vector<int>& moving,
                 const StaticGeoms& fixed) {
  LEEWAY_DEMAND(emulates_mj_collision(m));
  for (int g : moving) {
    if (m.geom_contype[g] == 0 && m.geom_conaffinity[g] == 0) continue;
    Aabb q = geom_aabb(m, d, g);
    const double widen = m.geom_margin[g] + fixed.max_margin;
    q.lo.array() -= widen;
    q.hi.array() += widen;
    const bool hit = fixed.grid.any(
        q, [&](int i) { return geoms_in_contact(m, d, g, fixed.geoms[static_cast<size_t>(i)]); });
    if (hit) return true;
  }
  return false;
}

}  // namespace leeway
