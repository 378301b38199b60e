#pragma once
// Internal: an OSMesa OpenGL context made current on this thread, with a MuJoCo rendering context
// whose offscreen buffer has the requested size (not public API). MuJoCo 2.2.2 links no GL and
// finds the GL functions of whatever context is current, so the
// OSMesa context is made current before mjr_makeContext.

#include <mujoco/mujoco.h>

#include <vector>

#include "leeway/viz/render.hpp"

namespace leeway::detail {

//! An OSMesa context plus MuJoCo's mjrContext for `model`, rendering offscreen at width x height.
//! `model` must stay alive while the context lives; its vis.global.offwidth/offheight are set.
class OffscreenContext {
 public:
  //! @throws InputError on a size outside 16 .. 8192; std::runtime_error when OSMesa fails.
  OffscreenContext(mjModel& model, int width, int height);
  ~OffscreenContext();
  OffscreenContext(const OffscreenContext&) = delete;
  OffscreenContext& operator=(const OffscreenContext&) = delete;

  //! Makes this context the thread's current one (another context made or used since took its
  //! place): every render through it calls this first.
  void make_current();
  mjrContext& mjr() { return con_; }
  mjrRect viewport() const { return {0, 0, width_, height_}; }
  //! The offscreen buffer's pixels, rows top to bottom (mjr_readPixels gives them bottom-up).
  Image read() const;

 private:
  void* osmesa_ = nullptr;  // OSMesaContext
  std::vector<unsigned char> window_;
  mjrContext con_;
  bool con_made_ = false;
  int width_ = 0, height_ = 0;
};

//! Checks an image size. @throws InputError naming `what` and the value outside 16 .. 8192 pixels.
void check_image_size(int width, int height, const char* what);

}  // namespace leeway::detail
