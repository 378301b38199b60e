#pragma once
//! @file viewer.hpp
//! The browser viewer: one self-contained HTML file (three.js inlined, no network needed) with the
//! cell, the robot, the volume, the nominal path of the tool, a time slider along the path in
//! seconds, ghosts at the bounds and one slider per joint limited to the bounds at that time
//! (docs/cli.md, `leeway view`).

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "leeway/core/bounds_trajectory.hpp"
#include "leeway/core/box.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {

//! What the page shows.
struct ViewerContent {
  std::string title;                     //!< heading: the cell and what was bounded
  std::optional<BoundsTrajectory> path;  //!< the bounds in time; none: the bare cell at `q`
  Eigen::VectorXd q;                     //!< the configuration shown without a path
  std::vector<Box> volume;               //!< the volume's boxes (empty: none)
  std::string safety_mode;               //!< certified, sampled or none ("" without bounds)
  bool proven = false;                   //!< the certificate covers every box (certified mode)
  double margin = 0.0;                   //!< the certified clearance [m]
  std::string initial_volume = "fade";   //!< fade, on or off: the volume when the page opens
};

//! Limits and sources of the page.
struct ViewerOptions {
  //! Most boxes drawn (volume boxes plus the cell's geoms): beyond it the page is refused, not
  //! decimated (a thinned volume would show room that is not there).
  long max_boxes = 200'000;
  //! Time between the slider's stops [s]; longer paths get a longer step so that a path has at
  //! most kMaxViewerSamples stops.
  double dt = 1.0 / 30.0;
  //! Folder of Debian's libjs-three (three.min.js and examples/js/controls/OrbitControls.js).
  std::string three_dir;
};

//! Most stops of the time slider.
inline constexpr long kMaxViewerSamples = 4000;

//! Clearance [m] at and above which a link is drawn fully green (0 is red): the colour scale of
//! the robot's links by their distance to the obstacles at the nominal configuration.
inline constexpr double kViewerClearanceScale = 0.25;

//! The folder libjs-three was found in at build time, or $LEEWAY_THREE_DIR when it is set.
std::string default_three_dir();

//! Checks that the three.js files the page inlines are readable in `dir`.
//! @throws InputError naming the missing file (Debian: apt-get install libjs-three).
void require_three_js(const std::string& dir);

//! The page's data (the cell's bodies, joints and geoms, the samples of the path, the volume) as
//! JSON, binary arrays as base64 of little-endian float32 or float64.
//! @throws InputError when the boxes exceed options.max_boxes or the scene and path differ.
std::string viewer_data_json(const Scene& scene, const ViewerContent& content, const ViewerOptions& options);

//! The whole page. @throws InputError as viewer_data_json, and naming the file when three.js is
//! not in options.three_dir (Debian: apt-get install libjs-three).
std::string viewer_html(const Scene& scene, const ViewerContent& content, const ViewerOptions& options);

}  // namespace leeway
