#include "leeway/volume_world.hpp"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include <mujoco/mjxmacro.h>

#include "leeway/error.hpp"

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

VolumeModel::VolumeModel(const Scene& scene, int capacity) : scene_(&scene) {
  install_mujoco_error_handlers();
  if (capacity < 1) throw InputError("volume pool capacity " + std::to_string(capacity) + " must be >= 1");
  const std::string& path = scene.source();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot read the cell again to add the volume pool");
  std::stringstream text;
  text << in.rdbuf();
  std::string xml = text.str();
  const size_t close = xml.rfind("</worldbody>");
  if (close == std::string::npos)
    throw InputError(path + ": has no </worldbody> in the main file; leeway adds its volume body there");
  // A static body at the world origin, last in the tree, so its geoms are the model's last geoms.
  xml.insert(close, std::string("<body name=\"") + kVolumeBodyName +
                        "\"><geom name=\"leeway_volume_template\" type=\"box\" size=\"0.001 0.001 0.001\" "
                        "contype=\"0\" conaffinity=\"0\" group=\"5\" rgba=\"0.2 0.5 1 0.4\"/></body>");
  // Compile from a virtual file named next to the cell so that its relative includes resolve.
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  const std::string vname = path + ".leeway-volume.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), vname.c_str(), static_cast<int>(xml.size())) != 0)
    throw std::runtime_error("cannot allocate a MuJoCo VFS file");
  std::memcpy(vfs->filedata[vfs->nfile - 1], xml.data(), xml.size());
  char error[1024] = "";
  mjModel* m = mj_loadXML(vname.c_str(), vfs.get(), error, sizeof(error));
  mj_deleteVFS(vfs.get());
  if (!m) throw InputError(path + ": does not compile with the volume body added: " + std::string(error));
  model_.reset(m);
  take_mujoco_warnings();

  const mjModel& small = scene.model();
  pool_body_ = mj_name2id(m, mjOBJ_BODY, kVolumeBodyName);
  if (pool_body_ != m->nbody - 1 || m->ngeom != small.ngeom + 1 || m->geom_bodyid[m->ngeom - 1] != pool_body_)
    throw InputError(path +
                     ": leeway cannot place its volume body last in the model (is there a body named '" +
                     kVolumeBodyName + "' already?)");
  for (int g = 0; g < small.ngeom; ++g) {
    LEEWAY_DEMAND(m->geom_type[g] == small.geom_type[g] && m->geom_bodyid[g] == small.geom_bodyid[g]);
    // Links as the scene normalised them; obstacles and everything else off: the volume decides.
    const bool link = scene.role(g) == GeomRole::kLink;
    m->geom_contype[g] = link ? 1 : 0;
    m->geom_conaffinity[g] = 0;
  }
  first_pool_geom_ = m->ngeom - 1;
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
  model_ = grow_last_body_geoms(*model_, capacity - capacity_);
  capacity_ = capacity;
  model_->body_geomnum[pool_body_] = active_;
  model_->ngeom = first_pool_geom_ + active_;
  ++generation_;  // checkers must rebind to the new model
}

void VolumeModel::set_boxes(const std::vector<Box>& boxes) {
  const int n = static_cast<int>(boxes.size());
  if (n > capacity_) {
    int grown = capacity_;
    while (grown < n) grown *= 2;
    grow(grown);
  }
  mjModel& m = *model_;
  for (int i = 0; i < capacity_; ++i) {
    const int g = first_pool_geom_ + i;
    if (i < n) {
      const Box& b = boxes[static_cast<size_t>(i)];
      if (!b.center.allFinite() || !b.half_size.allFinite() || (b.half_size.array() <= 0).any())
        throw InputError("volume box #" + std::to_string(i) + " has a non-finite or non-positive size");
      Eigen::Matrix<double, 3, 3, Eigen::RowMajor> r = b.rotation;
      mju_mat2Quat(m.geom_quat + 4 * g, r.data());
      for (int k = 0; k < 3; ++k) {
        m.geom_pos[3 * g + k] = b.center[k];
        m.geom_size[3 * g + k] = b.half_size[k];
      }
      m.geom_rbound[g] = b.half_size.norm();
      m.geom_sameframe[g] = 0;
      m.geom_contype[g] = 0;
      m.geom_conaffinity[g] = 1;
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
  ++generation_;
}

DataPtr VolumeModel::make_data() const {
  // A copy of the size fields with the full pool: mjData's arrays then fit any active count.
  mjModel sizes = *model_;
  sizes.ngeom = first_pool_geom_ + capacity_;
  return leeway::make_data(sizes);
}

VolumeChecker::VolumeChecker(const VolumeModel& world)
    : world_(&world), robot_(world.scene()), data_(world.make_data()), data_capacity_(world.capacity()) {
  const Scene& scene = world.scene();
  const mjModel& small = scene.model();
  for (int b = 1; b < small.nbody; ++b)
    if (small.body_weldid[b] != 0) robot_bodies_.push_back(b);
  robot_geoms_ = scene.link_geoms();
}

void VolumeChecker::refresh() {
  if (data_capacity_ != world_->capacity()) {  // the pool grew: the model was rebuilt
    data_ = world_->make_data();
    data_capacity_ = world_->capacity();
  }
  // Static geoms (the pool, obstacles) are placed once per volume.
  mj_kinematics(&world_->model(), data_.get());
  generation_ = world_->generation();
}

bool VolumeChecker::in_collision(const Eigen::VectorXd& q) {
  if (generation_ != world_->generation()) refresh();
  robot_.set(q);
  const mjData& s = robot_.data();
  mjData& d = *data_;
  for (int b : robot_bodies_) {
    std::memcpy(d.xpos + 3 * b, s.xpos + 3 * b, 3 * sizeof(mjtNum));
    std::memcpy(d.xquat + 4 * b, s.xquat + 4 * b, 4 * sizeof(mjtNum));
    std::memcpy(d.xmat + 9 * b, s.xmat + 9 * b, 9 * sizeof(mjtNum));
    std::memcpy(d.xipos + 3 * b, s.xipos + 3 * b, 3 * sizeof(mjtNum));
    std::memcpy(d.ximat + 9 * b, s.ximat + 9 * b, 9 * sizeof(mjtNum));
  }
  for (int g : robot_geoms_) {
    std::memcpy(d.geom_xpos + 3 * g, s.geom_xpos + 3 * g, 3 * sizeof(mjtNum));
    std::memcpy(d.geom_xmat + 9 * g, s.geom_xmat + 9 * g, 9 * sizeof(mjtNum));
  }
  mj_collision(&world_->model(), &d);
  take_mujoco_warnings();  // a full contact buffer still answers "in collision"
  ++checks_;
  return d.ncon > 0;
}

}  // namespace leeway
