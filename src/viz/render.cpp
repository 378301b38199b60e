#include "leeway/viz/render.hpp"

#include <GL/osmesa.h>
#include <zlib.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <stdexcept>

#include "canvas.hpp"
#include "core/json_io.hpp"
#include "leeway/core/categorize.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/io/bounds_file.hpp"
#include "offscreen.hpp"

namespace leeway {
namespace detail {

void check_image_size(int width, int height, const char* what) {
  constexpr int kMin = 16, kMax = 8192;
  if (width < kMin || width > kMax || height < kMin || height > kMax)
    throw InputError(std::string(what) + " " + std::to_string(width) + "x" + std::to_string(height) +
                     " pixels: width and height must be from 16 to 8192");
}

// The context's window buffer [pixels a side]: only for making it current (MuJoCo renders into its
// own offscreen framebuffer).
constexpr int kWindow = 16;

OffscreenContext::OffscreenContext(mjModel& model, int width, int height) : width_(width), height_(height) {
  check_image_size(width, height, "image size");
  install_mujoco_error_handlers();
  // As MuJoCo's record sample: RGBA, 24-bit depth, 8-bit stencil; a small window buffer to make the
  // context current (MuJoCo renders into its own offscreen framebuffer).
  OSMesaContext ctx = OSMesaCreateContextExt(OSMESA_RGBA, 24, 8, 8, nullptr);
  if (!ctx) throw std::runtime_error("OSMesa could not create an OpenGL context");
  osmesa_ = ctx;
  window_.assign(4 * kWindow * kWindow, 0);
  if (!OSMesaMakeCurrent(ctx, window_.data(), GL_UNSIGNED_BYTE, kWindow, kWindow)) {
    OSMesaDestroyContext(ctx);
    throw std::runtime_error("OSMesa could not make its OpenGL context current");
  }
  model.vis.global.offwidth = width;
  model.vis.global.offheight = height;
  mjr_defaultContext(&con_);
  try {
    mjr_makeContext(&model, &con_, mjFONTSCALE_150);
  } catch (...) {
    OSMesaDestroyContext(ctx);
    throw;
  }
  con_made_ = true;
  mjr_setBuffer(mjFB_OFFSCREEN, &con_);
  if (con_.currentBuffer != mjFB_OFFSCREEN || con_.offWidth != width || con_.offHeight != height) {
    mjr_freeContext(&con_);
    OSMesaDestroyContext(ctx);
    throw std::runtime_error("MuJoCo could not make an offscreen buffer of " + std::to_string(width) + "x" +
                             std::to_string(height) + " pixels");
  }
}

void OffscreenContext::make_current() {
  if (!OSMesaMakeCurrent(static_cast<OSMesaContext>(osmesa_), window_.data(), GL_UNSIGNED_BYTE, kWindow,
                         kWindow))
    throw std::runtime_error("OSMesa could not make its OpenGL context current");
  mjr_setBuffer(mjFB_OFFSCREEN, &con_);
}

OffscreenContext::~OffscreenContext() {
  // mjr_freeContext frees the OpenGL objects of the current context: make it this one.
  if (con_made_ && osmesa_)
    OSMesaMakeCurrent(static_cast<OSMesaContext>(osmesa_), window_.data(), GL_UNSIGNED_BYTE, kWindow,
                      kWindow);
  if (con_made_) mjr_freeContext(&con_);
  if (osmesa_) OSMesaDestroyContext(static_cast<OSMesaContext>(osmesa_));
}

Image OffscreenContext::read() const {
  Image image;
  image.width = width_;
  image.height = height_;
  const size_t row = 3 * static_cast<size_t>(width_);
  std::vector<unsigned char> bottom_up(row * static_cast<size_t>(height_));
  mjr_readPixels(bottom_up.data(), nullptr, viewport(), &con_);
  image.rgb.resize(bottom_up.size());
  for (int y = 0; y < height_; ++y)
    std::memcpy(image.rgb.data() + row * static_cast<size_t>(y),
                bottom_up.data() + row * static_cast<size_t>(height_ - 1 - y), row);
  return image;
}

}  // namespace detail

namespace {

constexpr double kPi = 3.14159265358979323846;

void put_u32(std::string& out, unsigned long v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<char>((v >> s) & 0xff));
}

void put_chunk(std::string& out, const char* type, const std::string& data) {
  put_u32(out, data.size());
  const std::string body = std::string(type, 4) + data;
  out += body;
  put_u32(out, crc32(0L, reinterpret_cast<const Bytef*>(body.data()), static_cast<uInt>(body.size())));
}

// The camera's frame: forward (into the scene), up and right, as MuJoCo's free camera computes them.
void camera_frame(const RenderCamera& c, Eigen::Vector3d& pos, Eigen::Vector3d& forward,
                  Eigen::Vector3d& up) {
  const double ca = std::cos(c.azimuth), sa = std::sin(c.azimuth);
  const double ce = std::cos(c.elevation), se = std::sin(c.elevation);
  forward = {ce * ca, ce * sa, se};
  up = {-se * ca, -se * sa, ce};
  pos = c.lookat - c.distance * forward;
}

void check_camera(const RenderCamera& c) {
  if (!std::isfinite(c.azimuth) || !std::isfinite(c.elevation) || !std::isfinite(c.distance) ||
      !c.lookat.allFinite())
    throw InputError("camera: azimuth, elevation, distance and look-at point must be finite numbers");
  if (!(c.distance > 0)) throw InputError("camera distance " + format_number(c.distance) + " m must be > 0");
  if (std::abs(c.elevation) > kPi / 2 + 1e-12)
    throw InputError("camera elevation " + format_number(c.elevation) + " rad must be within [-pi/2, pi/2]");
}

}  // namespace

std::array<unsigned char, 3> Image::at(int x, int y) const {
  LEEWAY_DEMAND(x >= 0 && x < width && y >= 0 && y < height);
  const size_t i = 3 * (static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x));
  return {rgb[i], rgb[i + 1], rgb[i + 2]};
}

std::string encode_png(const Image& image) {
  LEEWAY_DEMAND(image.width > 0 && image.height > 0 &&
                image.rgb.size() == 3 * static_cast<size_t>(image.width) * static_cast<size_t>(image.height));
  std::string out("\x89PNG\r\n\x1a\n", 8);
  std::string header;
  put_u32(header, static_cast<unsigned long>(image.width));
  put_u32(header, static_cast<unsigned long>(image.height));
  header += std::string("\x08\x02\x00\x00\x00", 5);  // 8 bits, RGB, deflate, no filter method, no interlace
  put_chunk(out, "IHDR", header);
  // Each row starts with its filter type; 0 (none) keeps the encoder simple and its bytes fixed.
  const size_t row = 3 * static_cast<size_t>(image.width);
  std::string raw;
  raw.reserve((row + 1) * static_cast<size_t>(image.height));
  for (int y = 0; y < image.height; ++y) {
    raw.push_back('\0');
    raw.append(reinterpret_cast<const char*>(image.rgb.data()) + row * static_cast<size_t>(y), row);
  }
  uLongf size = compressBound(static_cast<uLong>(raw.size()));
  std::string packed(size, '\0');
  if (compress2(reinterpret_cast<Bytef*>(packed.data()), &size, reinterpret_cast<const Bytef*>(raw.data()),
                static_cast<uLong>(raw.size()), 6) != Z_OK)
    throw std::runtime_error("zlib could not compress the image");
  packed.resize(size);
  put_chunk(out, "IDAT", packed);
  put_chunk(out, "IEND", "");
  return out;
}

std::array<int, 2> png_size(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the PNG file");
  unsigned char head[24] = {};
  in.read(reinterpret_cast<char*>(head), sizeof(head));
  if (in.gcount() != sizeof(head) || std::memcmp(head, "\x89PNG\r\n\x1a\n", 8) != 0 ||
      std::memcmp(head + 12, "IHDR", 4) != 0)
    throw InputError(path + ": not a PNG file (no PNG signature and IHDR chunk)");
  auto u32 = [&head](int at) {
    return static_cast<int>((unsigned{head[at]} << 24) | (unsigned{head[at + 1]} << 16) |
                            (unsigned{head[at + 2]} << 8) | unsigned{head[at + 3]});
  };
  return {u32(16), u32(20)};
}

void write_png(const std::string& path, const Image& image) { write_file_atomic(path, encode_png(image)); }

RenderCamera frame_circle(const Eigen::Vector2d& center, double radius, double height, double fovy) {
  RenderCamera c;
  c.lookat = {center.x(), center.y(), 0.5 * height};
  c.distance = 1.05 * std::hypot(radius, 0.5 * height) / std::sin(0.5 * fovy);
  return c;
}

namespace {

// Which volume boxes are faded: those that meet the fade region, and those that could hide part of
// it (nearer to the camera than its far side, their picture overlapping its picture).
class FadeTest {
 public:
  FadeTest(const RenderRequest& r, double fovy) : r_(r), fovy_(fovy) {
    if (r.fade_region.isEmpty()) return;
    Eigen::Vector3d up;
    camera_frame(r.camera, pos_, forward_, up);
    far_ = -INFINITY;
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d p = r.fade_region.corner(static_cast<Eigen::AlignedBox3d::CornerType>(k));
      far_ = std::max(far_, forward_.dot(p - pos_));
      Eigen::Vector2d px;
      if (!project_point(r.camera, fovy, r.width, r.height, p, px)) px = Eigen::Vector2d::Zero();
      picture_.extend(px);
    }
  }
  bool operator()(const Box& b) const {
    if (r_.fade_region.isEmpty()) return false;
    const Eigen::AlignedBox3d box = aligned(b);
    if (r_.fade_region.intersects(box)) return true;
    Eigen::AlignedBox2d picture;
    double near = INFINITY;
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d p = box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(k));
      near = std::min(near, forward_.dot(p - pos_));
      Eigen::Vector2d px;
      if (!project_point(r_.camera, fovy_, r_.width, r_.height, p, px)) return true;  // around the camera
      picture.extend(px);
    }
    return near < far_ && picture.intersects(picture_);
  }

 private:
  const RenderRequest& r_;
  double fovy_;
  Eigen::Vector3d pos_ = Eigen::Vector3d::Zero(), forward_ = Eigen::Vector3d::UnitX();
  double far_ = 0;
  Eigen::AlignedBox2d picture_;
};

}  // namespace

Eigen::AlignedBox3d robot_extent(const Scene& scene, const std::vector<Eigen::VectorXd>& qs) {
  const mjModel& m = scene.model();
  DataPtr d = make_data(m);
  Eigen::AlignedBox3d out;
  for (const Eigen::VectorXd& q : qs) {
    scene.validate_configuration(q, "framed configuration");
    scene.set_qpos(*d, q);
    mj_kinematics(&m, d.get());
    for (const auto* geoms : {&scene.link_geoms(), &scene.base_geoms()})
      for (int g : *geoms)
        if (m.geom_type[g] != mjGEOM_PLANE) out.extend(aligned(geom_box(m, *d, g)));
  }
  return out;
}

Eigen::AlignedBox3d robot_neighbourhood(const Scene& scene, const Eigen::AlignedBox3d& robot, double near) {
  if (robot.isEmpty()) return robot;
  const Eigen::AlignedBox3d around(robot.min().array() - near, robot.max().array() + near);
  const mjModel& m = scene.model();
  DataPtr d = make_data(m);
  mj_kinematics(&m, d.get());  // obstacles do not move with the robot
  Eigen::AlignedBox3d out = robot;
  for (int g : scene.obstacle_geoms()) {
    if (m.geom_type[g] == mjGEOM_PLANE) continue;
    const Eigen::AlignedBox3d part = aligned(geom_box(m, *d, g)).intersection(around);
    if (!part.isEmpty()) out.extend(part);
  }
  return out;
}

RenderCamera frame_box(const Eigen::AlignedBox3d& region, const RenderCamera& direction, double fovy,
                       double aspect) {
  RenderCamera c = direction;
  if (region.isEmpty()) return c;
  c.lookat = region.center();
  // Half the diagonal, at least 10 cm: a point-sized region still gets a finite distance.
  const double radius = std::max(0.1, 0.5 * region.diagonal().norm());
  const double half_h = 0.5 * fovy, half_w = std::atan(aspect * std::tan(half_h));
  c.distance = 1.05 * radius / std::sin(std::min(half_h, half_w));
  return c;
}

Image render_legend(int width, double max_top, bool ghosts, bool faded) {
  if (width < 16) throw InputError("legend width " + std::to_string(width) + " pixels is below 16");
  detail::Drawing d;
  d.width = width;
  d.height = kLegendHeight;
  double x = 10;
  if (max_top > 0) {
    // The colour scale: 64 steps of height_colour, ticks at nice heights below it.
    constexpr int kSteps = 64;
    const double bar = std::min(240.0, 0.4 * width);
    for (int i = 0; i < kSteps; ++i) {
      const auto c = height_colour((i + 0.5) / kSteps * max_top, max_top);
      d.rect(x + bar * i / kSteps, 8, bar / kSteps + 0.5, 12, {c[0], c[1], c[2]}, {}, 0);
    }
    const detail::Ticks ticks = detail::nice_ticks(0, max_top, 4);
    for (size_t i = 0; i < ticks.values.size(); ++i) {
      const double tx = x + bar * ticks.values[i] / max_top;
      d.polyline({{tx, 20}, {tx, 24}}, {0, 0, 0}, 1);
      d.label(tx, 34, ticks.labels[i], 9, 1);
    }
    d.label(x, 48, "volume box top [m]", 9);
    x += bar + 24;
  }
  const double after_scale = x;
  auto swatch = [&](const detail::Rgb& c, const std::string& text) {
    d.rect(x, 8, 14, 12, c, {0.3, 0.3, 0.3}, 1);
    d.label(x + 20, 18, text, 9);
    x += 26 + detail::text_width(text, 9);
  };
  if (ghosts) {
    auto rgb = [](const std::array<float, 3>& t) { return detail::Rgb{t[0], t[1], t[2]}; };
    swatch(rgb(kLowerGhostTint), "ghost: joints at lower bound");
    swatch(rgb(kUpperGhostTint), "ghost: joints at upper bound");
  }
  if (faded) d.label(after_scale, 44, "boxes around and in front of the robot faded", 9);
  return detail::to_image(d);
}

Image stack_vertically(const std::vector<Image>& images) {
  if (images.empty()) throw InputError("no image to stack");
  Image out;
  out.width = images.front().width;
  for (const Image& i : images) {
    if (i.width != out.width)
      throw InputError("images of widths " + std::to_string(out.width) + " and " + std::to_string(i.width) +
                       " cannot be stacked");
    out.height += i.height;
    out.rgb.insert(out.rgb.end(), i.rgb.begin(), i.rgb.end());
  }
  return out;
}

Image tile_horizontally(const std::vector<Image>& images) {
  if (images.empty()) throw InputError("no image to tile");
  Image out;
  out.height = images.front().height;
  for (const Image& i : images) {
    if (i.height != out.height)
      throw InputError("images of heights " + std::to_string(out.height) + " and " +
                       std::to_string(i.height) + " cannot be tiled side by side");
    out.width += i.width;
  }
  out.rgb.resize(3 * static_cast<size_t>(out.width) * static_cast<size_t>(out.height));
  for (int y = 0; y < out.height; ++y) {
    size_t at = 3 * static_cast<size_t>(y) * static_cast<size_t>(out.width);
    for (const Image& i : images) {
      const size_t row = 3 * static_cast<size_t>(i.width);
      std::copy_n(i.rgb.begin() + static_cast<std::ptrdiff_t>(row * static_cast<size_t>(y)), row,
                  out.rgb.begin() + static_cast<std::ptrdiff_t>(at));
      at += row;
    }
  }
  return out;
}

double highest_top(const std::vector<Box>& boxes) {
  double top = 0;
  for (const Box& b : boxes) top = std::max(top, b.center.z() + b.half_size.z());
  return top;
}

std::array<float, 3> height_colour(double top, double max_top) {
  // Viridis at five stops, linearly interpolated.
  static constexpr float kStops[5][3] = {{0.267f, 0.005f, 0.329f},
                                         {0.229f, 0.322f, 0.546f},
                                         {0.128f, 0.567f, 0.551f},
                                         {0.369f, 0.789f, 0.383f},
                                         {0.993f, 0.906f, 0.144f}};
  double t = max_top > 0 ? top / max_top : 0.0;
  t = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0) * 4.0;
  const int i = std::min(3, static_cast<int>(t));
  const float f = static_cast<float>(t - i);
  std::array<float, 3> c{};
  for (int k = 0; k < 3; ++k) c[static_cast<size_t>(k)] = (1 - f) * kStops[i][k] + f * kStops[i + 1][k];
  return c;
}

std::vector<Eigen::VectorXd> ghost_configurations(const WaypointBounds& w, GhostMode mode) {
  std::vector<Eigen::VectorXd> out;
  if (mode == GhostMode::kCorners) {
    out.push_back(w.lower);
    out.push_back(w.upper);
  } else if (mode == GhostMode::kJoints) {
    for (Eigen::Index j = 0; j < w.q.size(); ++j) {
      if (!(w.upper[j] > w.lower[j])) continue;
      for (double v : {w.lower[j], w.upper[j]}) {
        if (v == w.q[j]) continue;
        Eigen::VectorXd q = w.q;
        q[j] = v;
        out.push_back(q);
      }
    }
  }
  return out;
}

bool project_point(const RenderCamera& camera, double fovy, int width, int height, const Eigen::Vector3d& p,
                   Eigen::Vector2d& pixel) {
  Eigen::Vector3d pos, forward, up;
  camera_frame(camera, pos, forward, up);
  const Eigen::Vector3d right = forward.cross(up);
  const Eigen::Vector3d r = p - pos;
  const double z = r.dot(forward);
  if (!(z > 0)) return false;
  const double f = 0.5 * height / std::tan(0.5 * fovy);  // focal length [pixels]
  pixel = {0.5 * width + f * r.dot(right) / z, 0.5 * height - f * r.dot(up) / z};
  return true;
}

namespace {

void mark_transparent(mjvGeom& g, const Eigen::Vector3d& campos) {
  g.transparent = 1;
  g.camdist = static_cast<float>((Eigen::Vector3d(g.pos[0], g.pos[1], g.pos[2]) - campos).norm());
}

// A ghost: the robot's moving geoms at the pose in `d`, translucent and tinted (lower-bound ghosts
// bluish, upper-bound ones reddish).
void add_ghost(const mjModel& m, mjData& d, mjvOption& opt, const Eigen::Vector3d& campos, bool lower,
               mjvScene& scn) {
  const int first = scn.ngeom;
  mjv_addGeoms(&m, &d, &opt, nullptr, mjCAT_DYNAMIC, &scn);
  for (int k = first; k < scn.ngeom; ++k) {
    mjvGeom& geom = scn.geoms[k];
    if (geom.objtype != mjOBJ_GEOM) {  // sites and decor of the ghost: leave them out
      geom.rgba[3] = 0;
      continue;
    }
    const float* tint = lower ? kLowerGhostTint.data() : kUpperGhostTint.data();
    for (int c = 0; c < 3; ++c) geom.rgba[c] = tint[c];
    geom.rgba[3] = 0.28f;
    geom.segid = -1;
    mark_transparent(geom, campos);
  }
}

void set_camera(const RenderCamera& c, mjvCamera& cam) {
  mjv_defaultCamera(&cam);
  cam.type = mjCAMERA_FREE;
  cam.azimuth = c.azimuth * 180 / kPi;
  cam.elevation = c.elevation * 180 / kPi;
  cam.distance = c.distance;
  for (int k = 0; k < 3; ++k) cam.lookat[k] = c.lookat[k];
}

}  // namespace

struct FrameRenderer::Impl {
  const Scene& scene;
  ModelPtr model;
  DataPtr data, ghost;
  mjvOption opt;
  mjvCamera cam;
  mjvScene scn;
  std::unique_ptr<detail::OffscreenContext> gl;
  Impl(const Scene& s) : scene(s) {}
  ~Impl() { mjv_freeScene(&scn); }
};

FrameRenderer::FrameRenderer(const Scene& scene, int width, int height, const RenderCamera& camera)
    : impl_(std::make_unique<Impl>(scene)) {
  detail::check_image_size(width, height, "video size");
  check_camera(camera);
  install_mujoco_error_handlers();
  Impl& r = *impl_;
  r.model.reset(mj_copyModel(nullptr, &scene.model()));
  if (!r.model) throw std::runtime_error("MuJoCo could not copy the cell's model");
  r.data = make_data(*r.model);
  r.ghost = make_data(*r.model);
  mjv_defaultOption(&r.opt);
  set_camera(camera, r.cam);
  mjv_defaultScene(&r.scn);
  mjv_makeScene(r.model.get(), &r.scn, 1000 + 3 * (r.model->ngeom + r.model->nsite + 16));
  r.gl = std::make_unique<detail::OffscreenContext>(*r.model, width, height);
}

FrameRenderer::~FrameRenderer() = default;

Image FrameRenderer::render(const Eigen::VectorXd& q, const std::vector<Eigen::VectorXd>& ghosts,
                            const Eigen::Vector3d& arrow_from, const Eigen::Vector3d& arrow) {
  Impl& r = *impl_;
  const mjModel& m = *r.model;
  r.scene.validate_configuration(q, "rendered configuration");
  r.scene.set_qpos(*r.data, q);
  mj_kinematics(&m, r.data.get());
  mj_camlight(&m, r.data.get());
  mjv_updateScene(&m, r.data.get(), &r.opt, nullptr, &r.cam, mjCAT_ALL, &r.scn);
  const Eigen::Vector3d campos(r.scn.camera[0].pos[0], r.scn.camera[0].pos[1], r.scn.camera[0].pos[2]);
  for (size_t i = 0; i < ghosts.size() && i < 2; ++i) {
    r.scene.set_qpos(*r.ghost, ghosts[i]);
    mj_kinematics(&m, r.ghost.get());
    add_ghost(m, *r.ghost, r.opt, campos, i % 2 == 0, r.scn);
  }
  if (arrow.norm() > 1e-6 && r.scn.ngeom < r.scn.maxgeom) {
    mjvGeom& g = r.scn.geoms[r.scn.ngeom++];
    g = mjvGeom{};
    const float rgba[4] = {0.1f, 0.85f, 0.2f, 1.0f};
    mjv_initGeom(&g, mjGEOM_ARROW, nullptr, nullptr, nullptr, rgba);
    const Eigen::Vector3d to = arrow_from + arrow;
    mjv_makeConnector(&g, mjGEOM_ARROW, 0.08, arrow_from.x(), arrow_from.y(), arrow_from.z(), to.x(), to.y(),
                      to.z());
    g.category = mjCAT_DECOR;
  }
  r.gl->make_current();
  mjr_render(r.gl->viewport(), &r.scn, &r.gl->mjr());
  return r.gl->read();
}

namespace {

void check_request(const Scene& scene, const RenderRequest& request) {
  detail::check_image_size(request.width, request.height, "image size");
  check_camera(request.camera);
  scene.validate_configuration(request.q, "rendered configuration");
  for (size_t i = 0; i < request.ghosts.size(); ++i)
    scene.validate_configuration(request.ghosts[i], "ghost configuration " + std::to_string(i));
  if (!(request.volume_alpha >= 0 && request.volume_alpha <= 1))
    throw InputError("volume opacity " + format_number(request.volume_alpha) + " must be within [0, 1]");
  if (!(request.faded_alpha >= 0 && request.faded_alpha <= 1))
    throw InputError("faded volume opacity " + format_number(request.faded_alpha) + " must be within [0, 1]");
}

}  // namespace

struct SceneRenderer::Impl {
  const Scene& scene;
  int width, height;
  size_t max_boxes, max_ghosts;
  ModelPtr model;
  DataPtr data, ghost;
  mjvScene scn;
  bool scn_made = false;
  std::unique_ptr<detail::OffscreenContext> gl;
  explicit Impl(const Scene& s) : scene(s) {}
  ~Impl() {
    if (scn_made) mjv_freeScene(&scn);
  }
};

SceneRenderer::SceneRenderer(const Scene& scene, int width, int height, size_t max_volume_boxes,
                             size_t max_ghosts)
    : impl_(std::make_unique<Impl>(scene)) {
  detail::check_image_size(width, height, "image size");
  install_mujoco_error_handlers();
  Impl& r = *impl_;
  r.width = width;
  r.height = height;
  r.max_boxes = max_volume_boxes;
  r.max_ghosts = max_ghosts;
  r.model.reset(mj_copyModel(nullptr, &scene.model()));
  if (!r.model) throw std::runtime_error("MuJoCo could not copy the cell's model");
  const mjModel& m = *r.model;
  const double ghost_geoms = static_cast<double>(max_ghosts) * (m.ngeom + m.nsite + 16);
  const double maxgeom = 1000.0 + m.ngeom + m.nsite + static_cast<double>(max_volume_boxes) + ghost_geoms;
  if (maxgeom > 50'000'000)
    throw InputError("too many boxes to render: " + std::to_string(static_cast<long long>(maxgeom)));
  r.data = make_data(m);
  r.ghost = make_data(m);
  mjv_defaultScene(&r.scn);
  mjv_makeScene(&m, &r.scn, static_cast<int>(maxgeom));
  r.scn_made = true;
  r.gl = std::make_unique<detail::OffscreenContext>(*r.model, width, height);
}

SceneRenderer::~SceneRenderer() = default;

Image SceneRenderer::render(const RenderRequest& request) {
  Impl& r = *impl_;
  check_request(r.scene, request);
  if (request.width != r.width || request.height != r.height || request.volume.size() > r.max_boxes ||
      request.ghosts.size() > r.max_ghosts)
    throw std::logic_error("SceneRenderer: a request larger than the renderer was made for");
  mjModel& m = *r.model;
  auto pose = [&](mjData& d, const Eigen::VectorXd& q) {
    r.scene.set_qpos(d, q);
    mj_kinematics(&m, &d);
    mj_camlight(&m, &d);
  };
  pose(*r.data, request.q);

  mjvOption opt;
  mjv_defaultOption(&opt);
  mjvCamera cam;
  set_camera(request.camera, cam);
  mjvScene& scn = r.scn;
  mjv_updateScene(&m, r.data.get(), &opt, nullptr, &cam, mjCAT_ALL, &scn);
  const Eigen::Vector3d campos(scn.camera[0].pos[0], scn.camera[0].pos[1], scn.camera[0].pos[2]);

  for (size_t i = 0; i < request.ghosts.size(); ++i) {
    pose(*r.ghost, request.ghosts[i]);
    add_ghost(m, *r.ghost, opt, campos, i % 2 == 0, scn);
  }

  // The volume: one box per volume box, coloured by the height of its top.
  const FadeTest fade(request, m.vis.global.fovy * kPi / 180);
  const double max_top = highest_top(request.volume);
  for (const Box& b : request.volume) {
    if (scn.ngeom >= scn.maxgeom) break;  // cannot happen: maxgeom counts every box
    mjtNum size[3], pos[3], mat[9];
    for (int k = 0; k < 3; ++k) {
      size[k] = b.half_size[k];
      pos[k] = b.center[k];
      for (int l = 0; l < 3; ++l) mat[3 * k + l] = b.rotation(k, l);
    }
    const auto c = height_colour(b.center.z() + b.half_size.z(), max_top);
    const bool faded = fade(b);
    const double alpha = faded ? request.faded_alpha : request.volume_alpha;
    const float rgba[4] = {c[0], c[1], c[2], static_cast<float>(alpha)};
    mjvGeom& geom = scn.geoms[scn.ngeom++];
    // mjv_makeScene does not clear its geoms and mjv_initGeom leaves the sorter's fields
    // (camdist, modelrbound, transparent) as they were: start from zeros so that the picture does
    // not depend on what the heap (or the previous frame) held (it did: --threads 1 and 2 gave
    // other PNGs).
    geom = mjvGeom{};
    mjv_initGeom(&geom, mjGEOM_BOX, size, pos, mat, rgba);
    geom.category = mjCAT_DECOR;
    if (alpha < 1) mark_transparent(geom, campos);
  }

  r.gl->make_current();
  mjr_render(r.gl->viewport(), &scn, &r.gl->mjr());
  return r.gl->read();
}

Image render_scene(const Scene& scene, const RenderRequest& request) {
  check_request(scene, request);  // bad input is refused before an OpenGL context is made
  SceneRenderer renderer(scene, request.width, request.height, request.volume.size(), request.ghosts.size());
  return renderer.render(request);
}

BoundsFileVolume read_bounds_volume(const std::string& path, const Scene& scene, bool require_volume) {
  BoundsFileVolume out;
  out.bounds = read_bounds(path, scene);
  const nlohmann::json j = detail::read_json_file(path, "bounds file");
  // A bounds file names the cell it was computed for (as given on the command line); a file for
  // another cell with the same robot passes read_bounds, so compare file names and box counts.
  if (j.contains("cell") && j.at("cell").is_string()) {
    const auto written = std::filesystem::path(j.at("cell").get<std::string>()).filename();
    const auto given = std::filesystem::path(scene.source()).filename();
    if (written != given)
      throw InputError(path + ": cell '" + j.at("cell").get<std::string>() + "' is not " + scene.source() +
                       " (the bounds file was computed for another cell)");
  }
  if (!j.contains("params") && !require_volume) return out;
  if (!j.contains("params"))
    throw InputError(path + ": has no 'params': its volume cannot be regenerated (an older bounds file)");
  out.params = params_from_json(j.at("params"), path + " 'params'");
  if (j.contains("boxes")) {
    if (!j.at("boxes").is_number_integer() || j.at("boxes").get<long long>() < 0 ||
        j.at("boxes").get<long long>() > std::numeric_limits<int>::max())
      throw InputError(path + ": 'boxes' " + j.at("boxes").dump() + " must be a count of boxes, 0 or more");
    out.recorded_boxes = j.at("boxes").get<int>();
  }
  std::vector<Eigen::VectorXd> nominal;
  for (const auto& w : out.bounds) nominal.push_back(w.q);
  const Categories categories = categorize(scene, nominal, out.params.categorize);
  out.volume = generate_volume(categories, out.params.height_map, out.params.volume);
  if (out.recorded_boxes >= 0 && out.recorded_boxes != static_cast<int>(out.volume.boxes.size()))
    throw InputError(path + ": 'boxes' is " + std::to_string(out.recorded_boxes) +
                     " but its path and 'params' in " + scene.source() + " give a volume of " +
                     std::to_string(out.volume.boxes.size()) +
                     " boxes (was the bounds file computed for another cell or version?)");
  return out;
}

}  // namespace leeway
