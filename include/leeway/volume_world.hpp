#pragma once
//! @file volume_world.hpp
//! The volume injected into MuJoCo: a pool of box geoms preallocated in the cell's model and edited
//! in place (docs/algorithm.md, "Injection"), and per-thread collision checks of the robot against it.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "leeway/box.hpp"
#include "leeway/kinematics.hpp"
#include "leeway/scene.hpp"

namespace leeway {

//! Name of the body leeway adds to the cell to hold the volume's geoms.
inline constexpr const char* kVolumeBodyName = "leeway_volume";

//! The cell's model plus a pool of box geoms for the volume. Robot links collide with active pool
//! geoms only (obstacles are disabled in this model; the DLR option adds their boxes to the pool).
class VolumeModel {
 public:
  //! Compiles the scene's file with an added static body `leeway_volume` holding one template box
  //! geom, then grows the pool to `capacity` geoms by rewriting the compiled model (MuJoCo's
  //! compiler is quadratic in the geom count: 16 s for 100,000 geoms, against ~20 ms this way).
  //! @throws InputError when the scene's file cannot be read or has no </worldbody>.
  VolumeModel(const Scene& scene, int capacity);

  //! Puts the boxes into the pool (positions, orientations, sizes, bounding radii, bitmasks) and
  //! shrinks the pool body's geom count to them so MuJoCo iterates only active boxes. Grows the
  //! pool when it is too small. Not thread-safe: call it before checkers run.
  void set_boxes(const std::vector<Box>& boxes);

  //! The model; its ngeom counts only the active pool geoms (see set_boxes()).
  const mjModel& model() const { return *model_; }
  //! An mjData sized for the whole pool (use this, not mj_makeData on model()).
  DataPtr make_data() const;
  const Scene& scene() const { return *scene_; }
  int capacity() const { return capacity_; }
  int active() const { return active_; }
  int first_pool_geom() const { return first_pool_geom_; }
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
};

//! Grows a compiled model's last body's geoms by replicating its last geom `extra` times, through
//! MuJoCo's binary model format (every array listed in mjxmacro.h with ngeom rows). Exposed for tests.
//! @throws std::runtime_error when the binary layout is not the one this MuJoCo writes.
ModelPtr grow_last_body_geoms(const mjModel& m, int extra);

//! Collision checks of the robot against a VolumeModel's active boxes, for one thread: kinematics
//! on the small scene model, the robot's poses copied into the big model's data, then mj_collision.
class VolumeChecker {
 public:
  explicit VolumeChecker(const VolumeModel& world);
  //! True when a robot link touches an active volume box at q. @throws InputError on a bad q.
  bool in_collision(const Eigen::VectorXd& q);
  //! Number of collision checks so far.
  long checks() const { return checks_; }
  //! The big model's data after the last check (contacts in data().contact).
  const mjData& data() const { return *data_; }

 private:
  void refresh();
  const VolumeModel* world_;
  RobotState robot_;
  DataPtr data_;
  int data_capacity_ = 0;
  std::uint64_t generation_ = ~std::uint64_t{0};
  std::vector<int> robot_bodies_;
  std::vector<int> robot_geoms_;
  long checks_ = 0;
};

}  // namespace leeway
