#pragma once
// `leeway render`: an offscreen picture of the cell, the robot at a waypoint, the volume and ghosts.

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cli/common.hpp"
#include "leeway/core/bounds.hpp"
#include "leeway/core/bounds_trajectory.hpp"
#include "leeway/core/params.hpp"
#include "leeway/core/scene.hpp"
#include "leeway/core/volume.hpp"

namespace leeway::cli {

//! The command line of `leeway render`.
struct RenderArgs {
  std::string cell;                 //!< MJCF file of the workcell
  std::string bounds;               //!< bounds file (its nominal path, intervals and volume)
  std::string from, to;             //!< keyframes of a path to bound instead
  std::string key;                  //!< keyframe to show without bounds (default: the first)
  std::string out;                  //!< PNG file to write
  int waypoint = -1;                //!< waypoint shown; -1: the last
  int strip = 0;                    //!< frames along the path side by side; 0: one picture
  std::string legend = "on";        //!< legend band under the picture: on or off
  std::string video;                //!< also an MP4 along the path ("": none)
  std::string camera;               //!< "az,el,dist" [rad, rad, m]; empty: framing the reach circle
  std::string lookat;               //!< "x,y,z" [m]; empty: the reach circle's centre
  std::string size = "1280x960";    //!< image size [pixels]
  std::string volume = "fade";      //!< draw the volume: fade (around the robot), on or off
  std::string frame = "robot";      //!< default camera: robot (and nearby obstacles) or volume
  std::string ghosts = "corners";   //!< ghosts: corners, joints or none
  std::string params;               //!< parameter file (with --from/--to)
  std::string preset = "leeway";    //!< parameter set (with --from/--to)
  std::string safety;               //!< safety mode (with --from/--to); empty: the preset's
  JointBoundsOptions joints;        //!< --bisect, --half-width (with --from/--to)
  int max_cells = 0;                //!< MAX_cells, used when max_cells_given
  bool max_cells_given = false;     //!< --max-cells was on the command line (set by the parser)
  int waypoints = 2;                //!< waypoints of the joint-linear path (with --from/--to)
  bool no_plan = false;             //!< refuse a colliding straight path instead of planning around it
  int threads = default_threads();  //!< worker threads
};

//! Adds --from, --to and --key (what is shown besides --bounds, which they exclude) to `sub`.
void add_shown_path_options(CLI::App* sub, RenderArgs& args, CLI::Option* bounds);
//! Adds the options of bounds computed on the path (--no-plan, --waypoints, --max-cells, --params,
//! the preset and joint options, --threads) to `sub`.
void add_shown_computation_options(CLI::App* sub, RenderArgs& args, CLI::Option* bounds);
//! @throws InputError on --from without --to (or the reverse), or --key with them.
void check_shown_path(const RenderArgs& args);
//! The parameters of bounds computed on the path: the preset, --params, --safety, --max-cells and
//! the joint options. @throws InputError on invalid parameters.
Params shown_params(const Scene& scene, const RenderArgs& args);
//! The configuration shown without bounds: --key, else the cell's first keyframe, else zeros.
Eigen::VectorXd shown_keyframe(const Scene& scene, const RenderArgs& args);

//! What a picture or the viewer shows: the bounds (from the file, or computed on the nominal path as
//! leeway bounds does), their volume, timing and safety record; no bounds for a bare cell.
struct RenderInput {
  std::vector<WaypointBounds> bounds;
  Volume volume;
  std::string what;                            //!< the file, or the path's label
  std::optional<BoundsTrajectory> trajectory;  //!< the bounds in time (the file's times)
  std::string safety_mode = "none";            //!< certified, sampled or none
  bool proven = false;                         //!< certified, every segment passed
  double margin = 0.0;                         //!< the certified clearance [m]
};

//! The bounds `args` asks for (--bounds, or --from/--to computed as leeway bounds does) with their
//! volume; `p` becomes the file's parameters. nullopt when the path was refused (already reported).
//! @throws InputError on a bounds file for another cell, a bad path or waypoint count.
std::optional<RenderInput> render_input(const RenderArgs& args, const Scene& scene, Params& p,
                                        bool show_volume);

//! Adds the `render` subcommand, parsing into `args`; returns it.
CLI::App* add_render(CLI::App& app, RenderArgs& args);

//! Runs `leeway render`: writes the PNG and returns kExitOk; kExitFindings when the straight path
//! between the keyframes collides (nothing written).
//! @throws InputError on a bad cell, bounds file, waypoint, camera, size or output path.
int run_render(const RenderArgs& args);

}  // namespace leeway::cli
