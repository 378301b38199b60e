#pragma once
//! @file collision.hpp
//! Collision checks whose cost does not grow with the static geoms: the robot's link
//! geoms against static geoms (the volume's pool, the real obstacles) through the midphase of
//! midphase.hpp, then MuJoCo's own narrowphase (mjCOLLISIONFUNC) on the few pairs left, with
//! mj_collision's filters, margins and bounding-sphere tests in its order. The answer "is there a
//! contact?" is mj_collision's (docs/algorithm.md, "Fast collision core"); `kMujoco` keeps the full
//! mj_collision pass as the reference.

#include <mujoco/mujoco.h>

#include <string>
#include <utility>
#include <vector>

#include "leeway/core/box.hpp"
#include "leeway/core/midphase.hpp"

namespace leeway {

//! Which pipeline answers "is the robot in contact?".
enum class CollisionChecker {
  kMidphase,  //!< leeway's midphase, then MuJoCo's narrowphase on the candidate pairs (default)
  kMujoco,    //!< MuJoCo's mj_collision over every geom pair (the reference; linear in the geoms)
};

//! "midphase" or "mujoco".
const char* checker_name(CollisionChecker c);
//! Parses checker_name()'s names. @throws InputError naming the value and the choices.
CollisionChecker parse_checker(const std::string& name);

//! True when any_contact() gives mj_collision's answer on this model: no explicit <pair>, no
//! <exclude> that removes a contact the bitmasks allow (excludes_a_contact()), no contact override,
//! contacts and constraints enabled, no contact-filter callback. Otherwise the checkers fall back to
//! mj_collision.
bool emulates_mj_collision(const mjModel& m);

//! The two bodies of the model's i-th <contact><exclude> (MuJoCo keeps them sorted by id).
std::pair<int, int> excluded_bodies(const mjModel& m, int i);

//! True when some <exclude> pairs two bodies with geoms whose contype/conaffinity would let them
//! touch: only then does the exclude change what mj_collision reports.
bool excludes_a_contact(const mjModel& m);

//! The static side of a contact query: geoms placed once, with their world AABBs indexed.
struct StaticGeoms {
  AabbGrid grid;           //!< grid index i is geoms[i]
  std::vector<int> geoms;  //!< geom ids
  double max_margin = 0;   //!< the largest geom_margin among them [m]

  //! Indexes `geoms` at their poses in `d` (after kinematics). Geoms that no contact can involve
  //! (contype and conaffinity both 0) are left out.
  void build(const mjModel& m, const mjData& d, const std::vector<int>& geoms);
};

//! World AABB of a geom at its pose in `d`: exact for boxes, the bounding sphere (geom_rbound) for
//! the other types, infinite for planes and geoms without a bounding radius.
Aabb geom_aabb(const mjModel& m, const mjData& d, int geom);

//! True when mj_collision on (m, d) would report a contact between geoms g1 and g2 at their poses in
//! d: mj_collideGeoms's filter, margin, bounding-sphere and plane tests, then its narrowphase
//! function's contact count (no contact is added to d).
bool geoms_in_contact(const mjModel& m, const mjData& d, int g1, int g2);

//! geoms_in_contact() without mj_collideGeoms's filter (bitmasks, same weld body, parent): the
//! margin, bounding-sphere and plane tests and MuJoCo's narrowphase function. For pairs whose
//! filtering is leeway's own, such as the robot's self-collision pairs (Scene::self_pairs()).
bool geoms_touch(const mjModel& m, const mjData& d, int g1, int g2);

//! True when mj_collision on (m, d) would report a contact between one of the `moving` geoms and
//! one of `fixed`: for each moving geom, the static geoms whose AABB meets its AABB widened by the
//! margins, then mj_collision's filter (contype/conaffinity, same weld body, parent filter), margin,
//! bounding-sphere and plane tests and narrowphase, in its order. Stops at the first contact.
//! Requires emulates_mj_collision(m). Thread-safe for distinct `d`.
bool any_contact(const mjModel& m, const mjData& d, const std::vector<int>& moving, const StaticGeoms& fixed);

}  // namespace leeway
