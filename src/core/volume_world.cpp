#include "leeway/core/volume_world.hpp"

#include <algorithm>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>

#include <mujoco/mjxmacro.h>

#include "leeway/core/collision.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/shape.hpp"

namespace leeway {
namespace {

// One mjModel array as listed by mjxmacro.h.
struct ArrayInfo {
  std::string name;
  size_t elem = 0;  // bytes per element
  bool ngeom_rows = false;
  long rows = 0;
  long cols = 0;
  const char* data = nullptr;
  size_t bytes() const { return elem * static_cast<size_t>(rows * cols); }
};

std::vector<ArrayInfo> model_arrays(const mjModel* m) {
  std::vector<ArrayInfo> out;
  // X-macro expansion from mjxmacro.h, kept as written:
  // clang-format off
  MJMODEL_POINTERS_PREAMBLE(m)
#define X(type, name, nr, nc)                                                                   \
  out.push_back({#name, sizeof(type), std::strcmp(#nr, "ngeom") == 0, static_cast<long>(m->nr), \
                 static_cast<long>(nc), reinterpret_cast<const char*>(m->name)});
  MJMODEL_POINTERS
#undef X
  (void)nuser_body, (void)nuser_jnt, (void)nuser_geom, (void)nuser_site, (void)nuser_cam;
  (void)nuser_tendon, (void)nuser_actuator, (void)nuser_sensor, (void)nq, (void)nv, (void)na, (void)nu;
  (void)nmocap;
  // clang-format on
  return out;
}

std::vector<std::pair<std::string, int>> model_ints(const mjModel* m) {
  std::vector<std::pair<std::string, int>> out;
#define X(name) out.emplace_back(#name, m->name);
  MJMODEL_INTS
#undef X
  return out;
}

size_t round_up(size_t n, size_t a) { return a <= 1 ? n : (n + a - 1) / a * a; }

// Loads a binary model from memory through MuJoCo's virtual file system.
ModelPtr load_mjb(const std::vector<char>& bytes) {
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  const char* name = "leeway_grown.mjb";
  if (mj_makeEmptyFileVFS(vfs.get(), name, static_cast<int>(bytes.size())) != 0)
    throw std::runtime_error("cannot allocate a MuJoCo VFS file for the grown model");
  std::memcpy(vfs->filedata[vfs->nfile - 1], bytes.data(), bytes.size());
  mjModel* m = mj_loadModel(name, vfs.get());
  mj_deleteVFS(vfs.get());
  if (!m) throw std::runtime_error("MuJoCo rejected the grown binary model");
  return ModelPtr(m);
}

}  // namespace

ModelPtr grow_last_body_geoms(const mjModel& m, int extra) {
  LEEWAY_DEMAND(extra >= 0 && m.ngeom > 0);
  const int body = m.geom_bodyid[m.ngeom - 1];
  if (m.body_geomadr[body] + m.body_geomnum[body] != m.ngeom)
    throw std::runtime_error("the last geom's body does not own the last geoms");

  // Learn this MuJoCo's binary layout from a model it saved. MuJoCo 2.2.2 writes a header
  // {54321, sizeof(mjtNum), number of size ints, number of arrays}, the size ints, mjOption,
  // mjVisual, mjStatistic, then every array of mjxmacro.h back to back; in memory each array
  // starts at an aligned offset, which nbuffer (a size int) accounts for.
  const int size = mj_sizeModel(&m);
  std::vector<char> saved(static_cast<size_t>(size));
  mj_saveModel(&m, nullptr, saved.data(), size);
  const auto ints = model_ints(&m);
  const auto arrays = model_arrays(&m);
  const size_t fixed = sizeof(mjOption) + sizeof(mjVisual) + sizeof(mjStatistic);
  constexpr int kHeaderInts = 4;
  int header[kHeaderInts];
  std::memcpy(header, saved.data(), sizeof(header));
  int first_size = 0;
  std::memcpy(&first_size, saved.data() + sizeof(header), sizeof(int));
  if (header[0] != 54321 || header[1] != static_cast<int>(sizeof(mjtNum)) ||
      header[2] != static_cast<int>(ints.size()) || header[3] != static_cast<int>(arrays.size()) ||
      first_size != m.nq)
    throw std::runtime_error("unknown MJB layout for MuJoCo " + std::string(mj_versionString()));
  // The array alignment that reproduces nbuffer.
  auto buffer_size = [&arrays](size_t align, long ngeom) {
    size_t offset = 0;
    for (const auto& arr : arrays) {
      offset = round_up(offset, align);
      offset += arr.elem * static_cast<size_t>((arr.ngeom_rows ? ngeom : arr.rows) * arr.cols);
    }
    return offset;
  };
  size_t align_buffer = 0;
  for (size_t a : {size_t{1}, size_t{8}, size_t{16}, size_t{32}, size_t{64}, size_t{128}})
    if (buffer_size(a, m.ngeom) == static_cast<size_t>(m.nbuffer)) {
      align_buffer = a;
      break;
    }
  if (align_buffer == 0) throw std::runtime_error("cannot reproduce mjModel.nbuffer from mjxmacro.h");

  // Sizes of the grown model.
  const long new_ngeom = m.ngeom + extra;
  const size_t new_nbuffer = buffer_size(align_buffer, new_ngeom);

  std::vector<char> out;
  out.reserve(saved.size() + static_cast<size_t>(extra) * 1024);
  auto put = [&out](const void* p, size_t n) {
    out.insert(out.end(), static_cast<const char*>(p), static_cast<const char*>(p) + n);
  };
  put(header, sizeof(header));
  for (const auto& [name, value] : ints) {
    int v = value;
    if (name == "ngeom") v = static_cast<int>(new_ngeom);
    if (name == "nbuffer") v = static_cast<int>(new_nbuffer);
    put(&v, sizeof(int));
  }
  put(saved.data() + sizeof(header) + sizeof(int) * ints.size(), fixed);
  for (const auto& arr : arrays) {
    if (arr.name == "body_geomnum") {
      std::vector<int> geomnum(m.body_geomnum, m.body_geomnum + m.nbody);
      geomnum[static_cast<size_t>(body)] += extra;
      put(geomnum.data(), arr.bytes());
      continue;
    }
    put(arr.data, arr.bytes());
    if (arr.ngeom_rows) {
      const size_t row = arr.elem * static_cast<size_t>(arr.cols);
      const char* last = arr.data + row * static_cast<size_t>(m.ngeom - 1);
      for (int i = 0; i < extra; ++i) put(last, row);
    }
  }
  ModelPtr grown = load_mjb(out);
  LEEWAY_DEMAND(grown->ngeom == new_ngeom);
  return grown;
}

namespace {

// The volume model's MJCF: the robot's link geoms (their types and sizes; poses are written per
// check) on one free body, and a static body holding `pool` template box geoms. Built from the
// scene's compiled model, so it needs neither the cell's file nor its includes. A mesh link is the
// box about its geom's origin that holds its hull, a height field link the cube of its bounding sphere.
std::string pool_xml(const Scene& scene, int pool) {
  const mjModel& m = scene.model();
  std::ostringstream x;
  x.precision(17);
  x << "<mujoco model=\"leeway volume model\"><worldbody><body name=\"leeway_robot\"><freejoint/>";
  for (int g : scene.link_geoms()) {
    const int type = m.geom_type[g];
    const mjtNum* size = m.geom_size + 3 * g;
    x << "<geom contype=\"1\" conaffinity=\"0\" margin=\"" << m.geom_margin[g] << "\" ";
    switch (type) {
      case mjGEOM_SPHERE:
        x << "type=\"sphere\" size=\"" << size[0] << "\"/>";
        break;
      case mjGEOM_CAPSULE:
        x << "type=\"capsule\" size=\"" << size[0] << " " << size[1] << "\"/>";
        break;
      case mjGEOM_CYLINDER:
        x << "type=\"cylinder\" size=\"" << size[0] << " " << size[1] << "\"/>";
        break;
      case mjGEOM_ELLIPSOID:
        x << "type=\"ellipsoid\" size=\"" << size[0] << " " << size[1] << " " << size[2] << "\"/>";
        break;
      case mjGEOM_BOX:
        x << "type=\"box\" size=\"" << size[0] << " " << size[1] << " " << size[2] << "\"/>";
        break;
      case mjGEOM_MESH: {  // the box about the geom's origin that holds its hull
        const HullExtent e = hull_extent(m, g);
        const Eigen::Vector3d h =
            (e.centre - e.half_size).cwiseAbs().cwiseMax((e.centre + e.half_size).cwiseAbs());
        x << "type=\"box\" size=\"" << h[0] << " " << h[1] << " " << h[2] << "\"/>";
        break;
      }
      default: {  // height field: the cube of its bounding sphere
        const double r = m.geom_rbound[g] > 0 ? m.geom_rbound[g] : 1.0;
        x << "type=\"box\" size=\"" << r << " " << r << " " << r << "\"/>";
      }
    }
  }
  x << "</body><body name=\"" << kVolumeBodyName << "\">";
  for (int i = 0; i < pool; ++i)
    x << "<geom type=\"box\" size=\"0.001 0.001 0.001\" contype=\"0\" conaffinity=\"0\" group=\"5\" "
         "rgba=\"0.2 0.5 1 0.4\"/>";
  x << "</body></worldbody></mujoco>";
  return x.str();
}

ModelPtr compile_xml(const std::string& xml, const std::string& what) {
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  const char* name = "leeway-volume-model.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), name, static_cast<int>(xml.size())) != 0)
    throw std::runtime_error("cannot allocate a MuJoCo VFS file");
  std::memcpy(vfs->filedata[vfs->nfile - 1], xml.data(), xml.size());
  char error[1024] = "";
  mjModel* m = mj_loadXML(name, vfs.get(), error, sizeof(error));
  mj_deleteVFS(vfs.get());
  take_mujoco_warnings();
  if (!m) throw InputError(what + ": the volume model does not compile: " + std::string(error));
  return ModelPtr(m);
}

}  // namespace

VolumeModel::VolumeModel(const Scene& scene, int capacity, Growth growth) : scene_(&scene), growth_(growth) {
  if (capacity < 1) throw InputError("volume pool capacity " + std::to_string(capacity) + " must be >= 1");
  model_ = compile_xml(pool_xml(scene, 1), scene.source());
  small_ = ModelPtr(mj_copyModel(nullptr, model_.get()));
  const mjModel& m = *model_;
  pool_body_ = mj_name2id(&m, mjOBJ_BODY, kVolumeBodyName);
  LEEWAY_DEMAND(pool_body_ == m.nbody - 1 && m.ngeom == static_cast<int>(scene.link_geoms().size()) + 1);
  for (int k = 0; k < static_cast<int>(scene.link_geoms().size()); ++k) link_geoms_.push_back(k);
  first_pool_geom_ = m.ngeom - 1;
  capacity_ = 1;
  active_ = 1;  // the template, until set_boxes()
  grow(capacity);
  model_->body_geomnum[pool_body_] = 0;
  model_->ngeom = first_pool_geom_;
  active_ = 0;
}

void VolumeModel::grow(int capacity) {
  if (capacity <= capacity_) return;
  model_->ngeom = first_pool_geom_ + capacity_;  // the whole pool, as compiled
  model_->body_geomnum[pool_body_] = capacity_;
  bool grown = false;
  if (growth_ == Growth::kBinary) try {
      model_ = grow_last_body_geoms(*model_, capacity - capacity_);
      grown = true;
    } catch (const std::runtime_error&) {
      growth_ = Growth::kXml;  // another MuJoCo's binary layout
    }
  if (!grown) {
    // Compile the pool from XML (quadratic in the pool size, but it
    // does not depend on the binary layout).
    model_ = compile_xml(pool_xml(*scene_, capacity), scene_->source());
    pool_body_ = mj_name2id(model_.get(), mjOBJ_BODY, kVolumeBodyName);
  }
  capacity_ = capacity;
  model_->body_geomnum[pool_body_] = active_;
  model_->ngeom = first_pool_geom_ + active_;
  ++generation_;  // checkers must rebind to the new model
}

void VolumeModel::set_boxes(const std::vector<Box>& boxes) {
  const int n = static_cast<int>(boxes.size());
  for (int i = 0; i < n; ++i) {
    const Box& b = boxes[static_cast<size_t>(i)];
    if (!b.center.allFinite() || !b.half_size.allFinite() || !b.rotation.allFinite() ||
        (b.half_size.array() <= 0).any())
      throw InputError("volume box #" + std::to_string(i) + " has a non-finite or non-positive size");
  }
  if (n > capacity_) {
    int grown = capacity_;
    while (grown < n) grown *= 2;
    grow(grown);
  }
  mjModel& m = *model_;
  std::vector<Aabb> aabbs(static_cast<size_t>(n));
  pool_xpos_.resize(3 * static_cast<size_t>(n));
  pool_xmat_.resize(9 * static_cast<size_t>(n));
  for (int i = 0; i < capacity_; ++i) {
    const int g = first_pool_geom_ + i;
    if (i < n) {
      const Box& b = boxes[static_cast<size_t>(i)];
      if (b.rotation == Eigen::Matrix3d::Identity()) {  // the height map's boxes: what mju gives
        const mjtNum unit[4] = {1, 0, 0, 0};
        std::memcpy(m.geom_quat + 4 * g, unit, sizeof(unit));
      } else {
        Eigen::Matrix<double, 3, 3, Eigen::RowMajor> r = b.rotation;
        mju_mat2Quat(m.geom_quat + 4 * g, r.data());
      }
      for (int k = 0; k < 3; ++k) {
        m.geom_pos[3 * g + k] = b.center[k];
        m.geom_size[3 * g + k] = b.half_size[k];
      }
      m.geom_rbound[g] = b.half_size.norm();
      m.geom_sameframe[g] = 0;
      m.geom_contype[g] = 0;
      m.geom_conaffinity[g] = 1;
      // mj_kinematics on the static pool body (identity pose): xpos = pos, xmat from the quaternion.
      for (int k = 0; k < 3; ++k)
        pool_xpos_[3 * static_cast<size_t>(i) + static_cast<size_t>(k)] = b.center[k];
      mju_quat2Mat(pool_xmat_.data() + 9 * i, m.geom_quat + 4 * g);
      // The pool body is the static world frame: the geom's world box is the box itself (the
      // quaternion round trip differs from b.rotation by rounding, far below the grid's 1e-9 m).
      const Eigen::Vector3d e = b.rotation.cwiseAbs() * b.half_size;
      aabbs[static_cast<size_t>(i)] = {b.center - e, b.center + e};
    } else {
      m.geom_contype[g] = 0;
      m.geom_conaffinity[g] = 0;
    }
  }
  // MuJoCo 2.2.2 visits a body's geoms by body_geomnum, and makes a pass over all ngeom geoms in
  // every mj_collision and mj_kinematics call (measured: ~12 ns per parked geom). The pool is last,
  // so shrinking both to the active boxes leaves only those; every array keeps its full length.
  m.body_geomnum[pool_body_] = n;
  m.ngeom = first_pool_geom_ + n;
  active_ = n;
  pool_.grid.build(aabbs);
  pool_.geoms.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) pool_.geoms[static_cast<size_t>(i)] = first_pool_geom_ + i;
  pool_.max_margin = 0;
  ++generation_;
}

DataPtr VolumeModel::make_data() const {
  // A copy of the size fields with the full pool: mjData's arrays then fit any active count.
  mjModel sizes = *model_;
  sizes.ngeom = first_pool_geom_ + capacity_;
  return leeway::make_data(sizes);
}

VolumeChecker::VolumeChecker(const VolumeModel& world)
    : world_(&world), robot_(world.scene()), checker_(world.scene().checker()) {
  if (!emulates_mj_collision(world.model())) checker_ = CollisionChecker::kMujoco;
  if (checker_ == CollisionChecker::kMidphase) {
    small_ = ModelPtr(mj_copyModel(nullptr, &world.narrowphase_model()));
    small_data_ = make_data(*small_);
  }
}

void VolumeChecker::refresh() {
  // The mujoco checker's data: sized for the whole pool, the static geoms placed once per volume.
  if (checker_ == CollisionChecker::kMujoco) {
    if (!data_ || data_capacity_ != world_->capacity()) {  // new, or the pool grew
      data_ = world_->make_data();
      data_capacity_ = world_->capacity();
    }
    mj_kinematics(&world_->model(), data_.get());
  }
  generation_ = world_->generation();
}

bool VolumeChecker::midphase_collision() {
  // The link geoms' poses, then every candidate box written into the template geom in turn.
  mjModel& m = *small_;
  mjData& d = *small_data_;
  const mjModel& pool = world_->model();
  const int slot = m.ngeom - 1;
  const std::vector<int>& links = world_->link_geoms();
  const StaticGeoms& boxes = world_->pool();
  for (int g : links) {
    Aabb q = geom_aabb(m, d, g);
    q.lo.array() -= m.geom_margin[g];
    q.hi.array() += m.geom_margin[g];
    // The link box's own face axes separate most candidates (a long link's AABB holds many cells
    // its oriented box does not reach): a gap of more than 1e-9 m along one of them means no
    // contact for the narrowphase either, so those pairs skip it.
    const bool is_box = m.geom_type[g] == mjGEOM_BOX && m.geom_margin[g] == 0;
    const Eigen::Map<const Eigen::Matrix<mjtNum, 3, 3, Eigen::RowMajor>> axes(d.geom_xmat + 9 * g);
    const Eigen::Map<const Eigen::Vector3d> centre(d.geom_xpos + 3 * g), half(m.geom_size + 3 * g);
    const bool hit = boxes.grid.any(q, [&](int i) {
      const int p = boxes.geoms[static_cast<size_t>(i)];
      if (is_box && pool.geom_margin[p] == 0) {
        const Eigen::Map<const Eigen::Matrix<mjtNum, 3, 3, Eigen::RowMajor>> b(world_->pool_xmat(i));
        const Eigen::Map<const Eigen::Vector3d> bc(world_->pool_xpos(i)), bh(pool.geom_size + 3 * p);
        // Columns of `axes` are the link's axes; of `b`, the box's. Projections on the link's axes.
        const Eigen::Vector3d offset = (axes.transpose() * (bc - centre)).cwiseAbs();
        const Eigen::Vector3d reach = half + (axes.transpose() * b).cwiseAbs() * bh;
        if (((offset - reach).array() > 1e-9).any()) return false;
      }
      std::memcpy(m.geom_size + 3 * slot, pool.geom_size + 3 * p, 3 * sizeof(mjtNum));
      m.geom_rbound[slot] = pool.geom_rbound[p];
      m.geom_contype[slot] = pool.geom_contype[p];
      m.geom_conaffinity[slot] = pool.geom_conaffinity[p];
      m.geom_margin[slot] = pool.geom_margin[p];
      std::memcpy(d.geom_xpos + 3 * slot, world_->pool_xpos(i), 3 * sizeof(mjtNum));
      std::memcpy(d.geom_xmat + 9 * slot, world_->pool_xmat(i), 9 * sizeof(mjtNum));
      return geoms_in_contact(m, d, g, slot);
    });
    if (hit) return true;
  }
  return false;
}

bool VolumeChecker::in_collision(const Eigen::VectorXd& q) {
  if (generation_ != world_->generation()) refresh();
  robot_.set(q);
  const mjData& s = robot_.data();
  mjData& d = checker_ == CollisionChecker::kMidphase ? *small_data_ : *data_;
  const std::vector<int>& links = world_->scene().link_geoms();
  for (size_t k = 0; k < links.size(); ++k) {
    const int from = links[k], to = world_->link_geoms()[k];
    std::memcpy(d.geom_xpos + 3 * to, s.geom_xpos + 3 * from, 3 * sizeof(mjtNum));
    std::memcpy(d.geom_xmat + 9 * to, s.geom_xmat + 9 * from, 9 * sizeof(mjtNum));
  }
  ++checks_;
  if (checker_ == CollisionChecker::kMidphase) return midphase_collision();
  prevent_contact_warnings(d);  // a full contact buffer still answers "in collision"
  mj_collision(&world_->model(), &d);
  return d.ncon > 0;
}

}  // namespace leeway
