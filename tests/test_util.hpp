#pragma once
// Test support: MJCF strings written to temporary files, the CLI run as a subprocess, and a fixture
// that turns any MuJoCo warning into a test failure.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include <sys/wait.h>

#include "leeway/core/error.hpp"
#include "leeway/core/mujoco_util.hpp"

// LEEWAY_TEST_ASAN: this build runs under AddressSanitizer (LEEWAY_SANITIZE=address, gcc or clang).
#if defined(__SANITIZE_ADDRESS__)
#define LEEWAY_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define LEEWAY_TEST_ASAN 1
#endif
#endif

namespace leeway::test {

//! The whole content of a file, byte for byte ("" when it cannot be read).
inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

//! The message of the InputError `f` throws, or "(no InputError)" when it throws none.
inline std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

//! `n` samples scaled by LEEWAY_TEST_SAMPLE_SHARE (a share in (0, 1], default 1; at least 1): the
//! sanitizer builds run the long sampling tests on a share of their samples, every code path still
//! run (scripts/sanitize.sh).
inline int scaled_count(int n) {
  const char* env = std::getenv("LEEWAY_TEST_SAMPLE_SHARE");
  const double share = env ? std::atof(env) : 1.0;
  return share > 0 && share < 1 ? std::max(1, static_cast<int>(n * share)) : n;
}

//! A temporary directory removed when the object dies.
class TempDir {
 public:
  TempDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "leeway_test_XXXXXX").string();
    path_ = ::mkdtemp(tmpl.data());
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  //! Writes `text` to `name` inside the directory and returns its path.
  std::string write(const std::string& name, const std::string& text) const {
    const auto p = path_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

//! Output and exit code of a CLI invocation.
struct CliResult {
  int exit_code = -1;
  std::string out;  // stdout and stderr together
};

//! Runs `program` with `args` (a shell-quoted string); stdout and stderr together.
inline CliResult run_program(const std::string& program, const std::string& args) {
  const std::string cmd = program + " " + args + " 2>&1";
  CliResult r;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf{};
  size_t n = 0;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) r.out.append(buf.data(), n);
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

//! Runs the leeway program with `args` (a shell-quoted string).
inline CliResult run_cli(const std::string& args) { return run_program(LEEWAY_CLI, args); }

//! Path of a bundled workcell.
inline std::string workcell(const std::string& name) {
  return std::string(LEEWAY_MJCF_DIR) + "/workcells/" + name + ".xml";
}

//! Fails the test on any MuJoCo warning raised on the test's thread; `Base` is ::testing::Test or
//! a ::testing::TestWithParam.
template <class Base = ::testing::Test>
class MujocoTestOf : public Base {
 protected:
  void SetUp() override {
    install_mujoco_error_handlers();
    take_mujoco_warnings();
  }
  void TearDown() override {
    for (const auto& w : take_mujoco_warnings()) ADD_FAILURE() << "MuJoCo warning: " << w;
  }
};
using MujocoTest = MujocoTestOf<>;

//! The Dallara cell with a box wall across the joint-linear path from home to patch, written into
//! `dir` (cells/wall.xml, with a link to the bundled robots so its include resolves).
inline std::string dallara_with_wall(const TempDir& dir) {
  std::filesystem::create_directories(dir.path() / "cells");
  if (!std::filesystem::exists(dir.path() / "robots"))
    std::filesystem::create_directory_symlink(std::string(LEEWAY_MJCF_DIR) + "/robots",
                                              dir.path() / "robots");
  std::ifstream in(workcell("dallara"));
  std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  xml.replace(xml.find("</worldbody>"), 0,
              R"(<geom name="wall" type="box" pos="1.151 -0.706 0.9" size="0.55 0.05 0.9" euler="0 0 -0.55")"
              R"( contype="0" conaffinity="1"/>)"
              "\n");
  return dir.write("cells/wall.xml", xml);
}

//! Parses a JSON file.
inline nlohmann::json read_json(const std::filesystem::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

//! A serial chain of n hinges as tools/chain_cell.py writes it: about z and y in turn, 1.6 m in all,
//! a 6 cm box per link on a fixed base, every joint's range `range` ("-3 3") [rad], the wall geom
//! (0.05 x 1 x 1 half-size) at `wall_pos` ("0.9 0 1"); keyframes a (every joint 0) and b (joint i at
//! bent(i), its text as written into qpos).
inline std::string serial_chain_cell(int n, const std::string& range, const std::string& wall_pos,
                                     const std::function<std::string(int)>& bent_joint) {
  const double seg = 1.6 / n;
  std::string bodies, closing, straight, bent;
  for (int i = 0; i < n; ++i) {
    bodies += "<body name=\"l" + std::to_string(i + 1) + "\" pos=\"0 0 " +
              (i == 0 ? "0.2" : std::to_string(seg)) + "\"><joint name=\"j" + std::to_string(i + 1) +
              "\" type=\"hinge\" axis=\"" + (i % 2 ? "0 1 0" : "0 0 1") + "\" range=\"" + range +
              "\" user=\"1.5\"/><geom name=\"g" + std::to_string(i + 1) +
              "\" type=\"box\" size=\"0.03 0.03 " + std::to_string(0.4 * seg) + "\" pos=\"0 0 " +
              std::to_string(0.5 * seg) + "\"/>\n";
    closing += "</body>";
    straight += " 0";
    bent += " " + bent_joint(i);
  }
  return R"(<mujoco model="chain">
  <compiler angle="radian" autolimits="true"/>
  <worldbody>
    <body name="base"><geom name="base_box" type="box" size="0.1 0.1 0.1" pos="0 0 0.1"/>
)" + bodies +
         "<site name=\"tool0\" pos=\"0 0 " + std::to_string(seg) + "\"/>" + closing + R"(</body>
    <geom name="wall" type="box" size="0.05 1 1" pos=")" +
         wall_pos + R"(" contype="0" conaffinity="1"/>
  </worldbody>
  <keyframe><key name="a" qpos=")" +
         straight.substr(1) + R"("/><key name="b" qpos=")" + bent.substr(1) + R"("/></keyframe>
</mujoco>
)";
}

//! A one-link arm: hinge j1 about z at (0, 0, 0.5), a 1 m box link along +x (half-size
//! 0.5 x 0.05 x 0.05), tool0 at its tip. `world` is inserted into the world body.
inline std::string one_link_cell(const std::string& world, const std::string& keys = "") {
  return R"(<mujoco model="one-link">
  <compiler angle="radian" autolimits="true"/>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1" contype="0" conaffinity="0"/>
    <body name="base">
      <geom name="base_box" type="box" size="0.1 0.1 0.25" pos="0 0 0.25"/>
      <body name="link" pos="0 0 0.5">
        <joint name="j1" type="hinge" axis="0 0 1" range="-3 3" user="1.5"/>
        <geom name="link_box" type="box" size="0.5 0.05 0.05" pos="0.5 0 0"/>
        <site name="tool0" pos="1 0 0"/>
      </body>
    </body>
)" + world +
         R"(
  </worldbody>
  <keyframe>
)" + keys +
         R"(
  </keyframe>
</mujoco>
)";
}

//! Cross slides: joint x (slide along x, body 'carriage' at z = 0.5), then joint y (slide along y)
//! carry a 2 cm cube (cube_box, half-size 0.01, tool0 at its centre); both ranges [-1, 2] m.
//! `world` is inserted into the world body.
inline std::string cross_slide_cell(const std::string& world) {
  return R"(<mujoco model="cross_slide">
  <compiler angle="radian" autolimits="true"/>
  <worldbody>
    <body name="carriage" pos="0 0 0.5">
      <joint name="x" type="slide" axis="1 0 0" range="-1 2"/>
      <inertial pos="0 0 0" mass="1" diaginertia="0.1 0.1 0.1"/>
      <body name="cube">
        <joint name="y" type="slide" axis="0 1 0" range="-1 2"/>
        <geom name="cube_box" type="box" size="0.01 0.01 0.01"/>
        <site name="tool0"/>
      </body>
    </body>
    )" + world +
         R"(
  </worldbody>
</mujoco>
)";
}

//! A three-link arm for the self-collision rule (as tests/bad_input/cells/self_collide.xml): a fixed
//! base (base_box), hinges j1 about z at (0, 0, 0.2) (l1_box), j2 about y at 0.4 m (l2_box, 0.6 m up)
//! and j3 about y at 1.0 m (l3_box, 0.6 m along +x at zero), a body 'tool' welded to link3 (tool_box,
//! tool0 at its tip) and the obstacle 'block' on body 'stand'. `top` goes beside <worldbody>
//! (<contact>, <custom>); `keys` into <keyframe>. At j3 = pi/2 l3 and the tool fold down into l1.
inline std::string three_link_cell(const std::string& top = "", const std::string& keys = "") {
  return R"(<mujoco model="three-link">
  <compiler angle="radian" autolimits="true"/>
)" + top +
         R"(
  <worldbody>
    <body name="base">
      <geom name="base_box" type="box" size="0.2 0.2 0.1" pos="0 0 0.1"/>
      <body name="link1" pos="0 0 0.2">
        <joint name="j1" type="hinge" axis="0 0 1" range="-3 3" user="1.5"/>
        <geom name="l1_box" type="box" size="0.1 0.1 0.1" pos="0 0 0.1"/>
        <body name="link2" pos="0 0 0.2">
          <joint name="j2" type="hinge" axis="0 1 0" range="-2 2" user="1.5"/>
          <geom name="l2_box" type="box" size="0.05 0.05 0.3" pos="0 0 0.3"/>
          <body name="link3" pos="0 0 0.6">
            <joint name="j3" type="hinge" axis="0 1 0" range="-3 3" user="1.5"/>
            <geom name="l3_box" type="box" size="0.3 0.04 0.04" pos="0.3 0 0"/>
            <body name="tool" pos="0.6 0 0">
              <geom name="tool_box" type="box" size="0.05 0.05 0.05" pos="0.05 0 0"/>
              <site name="tool0" pos="0.1 0 0"/>
            </body>
          </body>
        </body>
      </body>
    </body>
    <body name="stand" pos="-1.5 0 0">
      <geom name="block" type="box" pos="0 0 0.5" size="0.1 0.1 0.5" contype="0" conaffinity="1"/>
    </body>
  </worldbody>
  <keyframe>
    <key name="a" qpos="0 0 0"/>
)" + keys +
         R"(
  </keyframe>
</mujoco>
)";
}

}  // namespace leeway::test
