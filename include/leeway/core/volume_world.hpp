#pragma once
//! @file volume_world.hpp
//! The volume injected into MuJoCo: a pool of box geoms preallocated in a MuJoCo model of the robot's
//! links and edited in place (docs/algorithm.md, "Injection"), and per-thread collision checks of
//! the robot against it (collision.hpp: the midphase by default, mj_collision as the reference).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "leeway/core/box.hpp"
#include "leeway/core/collision.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {

//! Name of the body leeway adds to the cell to hold the volume's geoms.
inline constexpr const char* kVolumeBodyName = "leeway_volume";

//! A MuJoCo model of the robot's link geoms plus a pool of box geoms for the volume. Links collide
//! with active pool geoms only (the real obstacles are not in this model; the DLR option adds their
//! boxes to the pool). Keeps a pointer to `scene`, which must outlive it.
class VolumeModel {
 public:
  //! Builds, from the scene's compiled model (not its file), an MJCF of the link geoms (same types
  //! and sizes, on one free body: their poses are written per check) and a static body
  //! `leeway_volume` holding one template box geom, compiles it, then grows the pool to `capacity`
  //! geoms by rewriting the compiled model through MuJoCo's binary format (MuJoCo's compiler is
  //! quadratic in the geom count: ~20 s for 100,000 geoms; ~20 ms this
  //! way). When the binary layout is not the one this code knows (another MuJoCo), the pool is
  //! compiled from XML instead.
  //! `growth` kXml forces the XML path (tests compare the two).
  //! @throws InputError when capacity < 1.
  enum class Growth { kBinary, kXml };
  VolumeModel(const Scene& scene, int capacity, Growth growth = Growth::kBinary);

  //! The pool a volume of at most `max_cells` height-map cells needs: one box per cell, and one per
  //! obstacle geom (volume.add_obstacle_boxes), so set_boxes() never has to grow it.
  static int capacity_for(const Scene& scene, int max_cells) {
    return max_cells + static_cast<int>(scene.obstacle_geoms().size());
  }

  //! Puts the boxes into the pool (positions, orientations, sizes, bounding radii, bitmasks),
  //! shrinks the pool body's geom count to them so MuJoCo iterates only active boxes, and indexes
  //! them for the midphase. Grows the pool when it is too small. Not thread-safe: call it before
  //! checkers run. @throws InputError on a non-finite or non-positive box.
  void set_boxes(const std::vector<Box>& boxes);

  //! The model; its ngeom counts only the active pool geoms (see set_boxes()).
  const mjModel& model() const { return *model_; }
  //! An mjData sized for the whole pool (use this, not mj_makeData on model()).
  DataPtr make_data() const;
  const Scene& scene() const { return *scene_; }
  int capacity() const { return capacity_; }
  int active() const { return active_; }
  int first_pool_geom() const { return first_pool_geom_; }
  //! The model's geom of each of scene().link_geoms(), in that order.
  const std::vector<int>& link_geoms() const { return link_geoms_; }
  //! The active pool geoms, indexed for the midphase.
  const StaticGeoms& pool() const { return pool_; }
  //! The link geoms and one template pool geom, as compiled (the midphase's narrowphase model:
  //! each candidate box is written into the template, so a checker needs no pool-sized data).
  const mjModel& narrowphase_model() const { return *small_; }
  //! World position [m] and rotation matrix (row-major) of active pool box i, as mj_kinematics
  //! computes them for the pool geom.
  const mjtNum* pool_xpos(int i) const { return pool_xpos_.data() + 3 * i; }
  const mjtNum* pool_xmat(int i) const { return pool_xmat_.data() + 9 * i; }
  //! Incremented by every set_boxes(); checkers refresh their static data when it changes.
  std::uint64_t generation() const { return generation_; }

 private:
  void grow(int capacity);
  const Scene* scene_;
  ModelPtr model_;
  int pool_body_ = -1;
  int first_pool_geom_ = -1;
  int capacity_ = 0;
  int active_ = 0;
  std::uint64_t generation_ = 0;
  std::vector<int> link_geoms_;
  StaticGeoms pool_;
  ModelPtr small_;
  std::vector<mjtNum> pool_xpos_, pool_xmat_;
  Growth growth_ = Growth::kBinary;
};

//! Grows a compiled model's last body's geoms by replicating its last geom `extra` times, through
//! MuJoCo's binary model format (every array listed in mjxmacro.h with ngeom rows). Exposed for tests.
//! @throws std::runtime_error when the binary layout is not the one this MuJoCo writes.
ModelPtr grow_last_body_geoms(const mjModel& m, int extra);

//! Collision checks of the robot against a VolumeModel's active boxes, for one thread: kinematics
//! on the scene model, the link geoms' poses copied into the volume model's data, then the scene's
//! checker (Scene::checker()): the midphase and MuJoCo's narrowphase, or mj_collision. Keeps a
//! pointer to `world`, which must outlive it.
class VolumeChecker {
 public:
  explicit VolumeChecker(const VolumeModel& world);
  //! True when a robot link touches an active volume box at q. @throws InputError on a bad q.
  bool in_collision(const Eigen::VectorXd& q);
  //! True when two robot geoms (Scene::self_pairs()) touch at the configuration of the last
  //! in_collision() call.
  bool touches_itself() const { return robot_.self_contact() >= 0; }
  //! Number of collision checks so far.
  long checks() const { return checks_; }
  //! The data of the last check: with the mujoco checker the pool model's, contacts in
  //! data().contact; with the midphase the narrowphase model's, without contacts.
  const mjData& data() const { return data_ ? *data_ : *small_data_; }
  //! The checker in use (the scene's, or mujoco when the model needs mj_collision).
  CollisionChecker checker() const { return checker_; }

 private:
  void refresh();
  bool midphase_collision();
  const VolumeModel* world_;
  RobotState robot_;
  ModelPtr small_;  // the narrowphase model (midphase)
  DataPtr small_data_;
  DataPtr data_;  // the pool model's data (mujoco checker)
  int data_capacity_ = 0;
  std::uint64_t generation_ = ~std::uint64_t{0};
  long checks_ = 0;
  CollisionChecker checker_ = CollisionChecker::kMidphase;
};

}  // namespace leeway
