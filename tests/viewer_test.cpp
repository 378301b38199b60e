// The browser viewer (leeway view): the page's data against hand-worked values on the one-link arm,
// its limits and bad input, and the page itself in headless Chromium (skipped without it).
#include <gtest/gtest.h>

#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>

#include "leeway/core/error.hpp"
#include "leeway/viz/viewer.hpp"
#include "png_util.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::run_cli;
using test::workcell;

// Decodes base64 (RFC 4648 with padding).
std::string unbase64(const std::string& text) {
  auto value = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    return c == '+' ? 62 : c == '/' ? 63 : -1;
  };
  std::string out;
  unsigned bits = 0;
  int count = 0;
  for (char c : text) {
    const int v = value(c);
    if (v < 0) break;  // padding
    bits = (bits << 6) | static_cast<unsigned>(v);
    count += 6;
    if (count >= 8) {
      count -= 8;
      out.push_back(static_cast<char>((bits >> count) & 0xff));
    }
  }
  return out;
}

template <typename T>
std::vector<T> numbers(const json& field) {
  const std::string raw = unbase64(field.get<std::string>());
  std::vector<T> out(raw.size() / sizeof(T));
  std::memcpy(out.data(), raw.data(), out.size() * sizeof(T));
  return out;
}

// The one-link arm (a 1 m link along x at 0.5 m height, turning about z) and a post: a 0.2 m cube
// centred at (0, 1.5, 0.5).
constexpr const char* kPost = R"(<geom name="post" type="box" size="0.1 0.1 0.1" pos="0 1.5 0.5"/>)";

class ViewerTest : public test::MujocoTest {
 protected:
  Scene scene() {
    return Scene::load(
        dir_.write("one_link.xml", test::one_link_cell(kPost, R"(<key name="home" qpos="0"/>)")));
  }
  // q from 0 to pi/2 in 1 s: bounds [-0.1, 0.2] at the start and [1.4, 1.6] at the end.
  static BoundsTrajectory quarter_turn() {
    const double half_pi = 1.5707963267948966;
    std::vector<WaypointBounds> w = {
        WaypointBounds(Eigen::VectorXd::Constant(1, 0.0), Eigen::VectorXd::Constant(1, -0.1),
                       Eigen::VectorXd::Constant(1, 0.2)),
        WaypointBounds(Eigen::VectorXd::Constant(1, half_pi), Eigen::VectorXd::Constant(1, 1.4),
                       Eigen::VectorXd::Constant(1, 1.6))};
    return BoundsTrajectory(w, {0.0, 1.0}, true);
  }
  static ViewerContent content_of(BoundsTrajectory path) {
    ViewerContent c;
    c.title = "one-link";
    c.path = std::move(path);
    c.safety_mode = "certified";
    c.proven = true;
    c.margin = 0.001;
    return c;
  }
  test::TempDir dir_;
};

TEST_F(ViewerTest, SamplesTheBoundsAtTheSlidersStopsAsWorkedOutByHand) {
  const Scene s = scene();
  const json data = json::parse(viewer_data_json(s, content_of(quarter_turn()), ViewerOptions{}));
  const json& path = data.at("path");
  // Stops every 1/30 s from 0 to 1 s: 31 of them (the last is the end, 30/30 s).
  ASSERT_EQ(path.at("count").get<int>(), 31);
  const auto t = numbers<double>(path.at("t"));
  const auto nominal = numbers<double>(path.at("nominal"));
  const auto lower = numbers<double>(path.at("lower"));
  const auto upper = numbers<double>(path.at("upper"));
  ASSERT_EQ(t.size(), 31u);
  EXPECT_DOUBLE_EQ(t[15], 0.5);
  // Halfway in time is halfway in s: the mean of the waypoints' values.
  EXPECT_NEAR(nominal[15], 0.7853981633974483, 1e-12);
  EXPECT_NEAR(lower[15], 0.65, 1e-12);
  EXPECT_NEAR(upper[15], 0.9, 1e-12);
  EXPECT_DOUBLE_EQ(lower[30], 1.4);
  EXPECT_DOUBLE_EQ(upper[0], 0.2);
  // The tool (1 m along the link) at (cos q, sin q, 0.5).
  const auto tool = numbers<float>(path.at("tool"));
  ASSERT_EQ(tool.size(), 93u);
  EXPECT_NEAR(tool[0], 1.0, 1e-6);
  EXPECT_NEAR(tool[3 * 15], std::cos(0.7853981633974483), 1e-6);
  EXPECT_NEAR(tool[3 * 15 + 1], std::sin(0.7853981633974483), 1e-6);
  EXPECT_NEAR(tool[3 * 30 + 2], 0.5, 1e-6);
  // The link's clearance to the post: at q = 0 the link spans y within +-0.05 and the post starts
  // at y = 1.4: 1.35 m; at q = pi/2 the link reaches y = 1: 0.4 m.
  const auto clearance = numbers<float>(path.at("clearance"));
  ASSERT_EQ(clearance.size(), 31u);
  EXPECT_NEAR(clearance[0], 1.35, 1e-5);
  EXPECT_NEAR(clearance[30], 0.4, 1e-5);
  EXPECT_EQ(data.at("safety").at("mode"), "certified");
  EXPECT_EQ(data.at("joints").at(0).at("name"), "j1");
  EXPECT_EQ(data.at("joints").at(0).at("unit"), "rad");
}

TEST_F(ViewerTest, TheBodyTreeAndGeomsAreTheModelsWithTheirRoles) {
  const Scene s = scene();
  const json data = json::parse(viewer_data_json(s, content_of(quarter_turn()), ViewerOptions{}));
  // world, base, link; the hinge on the link at its origin about z, robot joint 0.
  ASSERT_EQ(data.at("bodies").size(), 3u);
  const json& link = data.at("bodies").at(2);
  EXPECT_EQ(link.at("parent"), 1);
  EXPECT_EQ(link.at("pos"), json::array({0, 0, 0.5}));
  ASSERT_EQ(link.at("joints").size(), 1u);
  EXPECT_EQ(link.at("joints").at(0).at("axis"), json::array({0, 0, 1}));
  EXPECT_EQ(link.at("joints").at(0).at("index"), 0);
  std::map<std::string, std::string> roles;
  for (const json& g : data.at("geoms"))
    roles[g.at("type").get<std::string>() + "@" + g.at("body").dump()] = g.at("role");
  EXPECT_EQ(roles.at("box@2"), "link");
  EXPECT_EQ(roles.at("box@1"), "base");
  EXPECT_EQ(roles.at("box@0"), "obstacle");
  EXPECT_EQ(roles.at("plane@0"), "visual");  // the floor collides with nothing
}

TEST_F(ViewerTest, WithoutBoundsTheSlidersSpanTheJointLimits) {
  const Scene s = scene();
  ViewerContent c;
  c.q = Eigen::VectorXd::Constant(1, 0.25);
  const json data = json::parse(viewer_data_json(s, c, ViewerOptions{}));
  EXPECT_FALSE(data.contains("path"));
  EXPECT_EQ(data.at("q"), json::array({0.25}));
  // j1's range in the cell: -3 .. 3 rad.
  EXPECT_EQ(data.at("limits").at("lower"), json::array({-3.0}));
  EXPECT_EQ(data.at("limits").at("upper"), json::array({3.0}));
}

TEST_F(ViewerTest, VolumeBoxesAreInstancedNumbersWithTheirHeightColours) {
  const Scene s = scene();
  ViewerContent c = content_of(quarter_turn());
  Box low, high;
  low.center = {2, 0, 0.25};
  low.half_size = {0.1, 0.2, 0.25};
  high.center = {2, 1, 1};
  high.half_size = {0.1, 0.1, 1};
  c.volume = {low, high};
  const json volume = json::parse(viewer_data_json(s, c, ViewerOptions{})).at("volume");
  EXPECT_EQ(volume.at("count"), 2);
  EXPECT_DOUBLE_EQ(volume.at("max_top").get<double>(), 2.0);
  EXPECT_FALSE(volume.contains("rotation"));  // both are axis-aligned
  const auto boxes = numbers<float>(volume.at("boxes"));
  ASSERT_EQ(boxes.size(), 12u);
  EXPECT_EQ(boxes[0], 2.0f);
  EXPECT_EQ(boxes[4], 0.2f);
  EXPECT_EQ(boxes[11], 1.0f);
  // The colours are the scale's: the highest box has the top colour, the other the one at 0.5 m.
  const std::string colour = unbase64(volume.at("colour"));
  ASSERT_EQ(colour.size(), 6u);
  const auto top = height_colour(2.0, 2.0), quarter = height_colour(0.5, 2.0);
  EXPECT_EQ(static_cast<unsigned char>(colour[3]), std::lround(255 * top[0]));
  EXPECT_EQ(static_cast<unsigned char>(colour[1]), std::lround(255 * quarter[1]));
  EXPECT_EQ(volume.at("scale").size(), 9u);
}

TEST_F(ViewerTest, MoreBoxesThanTheLimitAreRefusedNotThinned) {
  const Scene s = scene();
  ViewerContent c = content_of(quarter_turn());
  c.volume.resize(11);
  ViewerOptions options;
  options.max_boxes = 10;
  const std::string error = test::error_of([&] { viewer_data_json(s, c, options); });
  EXPECT_NE(error.find("the volume has 11 boxes, more than the viewer's limit of 10"), std::string::npos)
      << error;
  // The default limit refuses a quarter of a million boxes.
  c.volume.resize(250'000);
  const std::string many = test::error_of([&] { viewer_data_json(s, c, ViewerOptions{}); });
  EXPECT_NE(many.find("the volume has 250000 boxes, more than the viewer's limit of 200000"),
            std::string::npos)
      << many;
  // The cell's own geoms count too: floor, base, link and post are 4.
  c.volume.resize(8);
  const std::string cell = test::error_of([&] { viewer_data_json(s, c, options); });
  EXPECT_NE(cell.find("have 12 geoms and boxes"), std::string::npos) << cell;
}

TEST_F(ViewerTest, PageInlinesThreeJsWithItsLicenceAndEscapesTheData) {
  const Scene s = scene();
  ViewerContent c = content_of(quarter_turn());
  c.title = "a </script> title";
  const std::string page = viewer_html(s, c, ViewerOptions{});
  EXPECT_NE(page.find("The MIT License. Copyright (c) 2010-2019 three.js authors"), std::string::npos);
  EXPECT_NE(page.find("THREE.OrbitControls"), std::string::npos);
  EXPECT_EQ(page.find("LEEWAY_DATA"), std::string::npos);
  EXPECT_EQ(page.find("src=\"http"), std::string::npos);  // nothing from the network
  EXPECT_NE(page.find("a <\\/script> title"), std::string::npos);
  // A data element ends where the page says, so the data parses whole.
  const size_t from = page.find("<script id=\"leeway-data\" type=\"application/json\">");
  ASSERT_NE(from, std::string::npos);
  const size_t start = page.find('>', from) + 1;
  const json data = json::parse(page.substr(start, page.find("</script>", start) - start));
  EXPECT_EQ(data.at("title"), "a </script> title");
}

TEST_F(ViewerTest, TwentyThousandBoxesMakeAPageOfAFewMegabytes) {
  const Scene s = scene();
  ViewerContent c = content_of(quarter_turn());
  for (int i = 0; i < 20000; ++i) {
    Box b;
    b.center = {0.01 * (i % 200), 0.01 * (i / 200), 0.3 + 0.001 * (i % 97)};
    b.half_size = {0.005, 0.005, 0.3 + 0.001 * (i % 97)};
    c.volume.push_back(b);
  }
  const std::string page = viewer_html(s, c, ViewerOptions{});
  // three.js r111 minified is 0.85 MB; each box adds 24 bytes of numbers and 3 of colour, as
  // base64 about 36 bytes: about 1.6 MB in all.
  EXPECT_LT(page.size(), 2'000'000u);
  EXPECT_GT(page.size(), 850'000u + 20000u * 30u);
}

TEST_F(ViewerTest, MissingThreeJsIsNamed) {
  const Scene s = scene();
  ViewerOptions options;
  options.three_dir = (dir_.path() / "nowhere").string();
  const std::string error = test::error_of([&] { viewer_html(s, content_of(quarter_turn()), options); });
  EXPECT_NE(error.find("nowhere/three.min.js: three.js is not there (Debian: apt-get install libjs-three"),
            std::string::npos)
      << error;
}

// ---- The command line and the page in a browser.

class CliViewTest : public test::MujocoTest {
 protected:
  // Bounds home -> patch on the Dallara cell with the thesis's parameters at MAX_cells 2000.
  std::string bounds_file() {
    const std::string out = path("b.json");
    if (!fs::exists(out)) {
      const auto r = run_cli("bounds " + workcell("dallara") +
                             " --from home --to patch --preset thesis --max-cells 2000 --out " + out);
      EXPECT_EQ(r.exit_code, 0) << r.out;
    }
    return out;
  }
  std::string path(const std::string& name) const { return (dir_.path() / name).string(); }
  test::TempDir dir_;
};

TEST_F(CliViewTest, WritesOnePageAndSaysWhatIsInIt) {
  const auto r =
      run_cli("view " + workcell("dallara") + " --bounds " + bounds_file() + " --out " + path("v.html"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("wrote " + path("v.html") + " ("), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("6 joint sliders"), std::string::npos) << r.out;
  EXPECT_TRUE(fs::exists(path("v.html")));
  const auto bare = run_cli("view " + workcell("dallara") + " --key patch --out " + path("bare.html"));
  ASSERT_EQ(bare.exit_code, 0) << bare.out;
  EXPECT_NE(bare.out.find("no bounds, 0 volume boxes"), std::string::npos) << bare.out;
}

TEST_F(CliViewTest, BadInputExitsTwoAndWritesNothing) {
  const std::string b = bounds_file();
  struct Case {
    std::string args, message;
  };
  const std::vector<Case> cases = {
      {"view " + workcell("dallara") + " --bounds " + b + " --out " + path("v.png"), ".html"},
      {"view " + workcell("dallara") + " --bounds " + b + " --out " + path("missing/v.html"), "missing"},
      {"view " + workcell("baltico") + " --bounds " + b + " --out " + path("v.html"), b},
      {"view " + workcell("dallara") + " --bounds " + b + " --max-boxes 10 --out " + path("v.html"),
       "more than the viewer's limit of 10"},
      {"view " + workcell("dallara") + " --bounds " + b + " --volume maybe --out " + path("v.html"),
       "--volume 'maybe'"},
      {"view " + workcell("dallara") + " --from home --out " + path("v.html"), "--from and --to go together"},
  };
  for (const Case& c : cases) {
    const auto r = run_cli(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.out;
    EXPECT_NE(r.out.find(c.message), std::string::npos) << c.args << "\n" << r.out;
    EXPECT_FALSE(fs::exists(path("v.html"))) << c.args;
  }
  // An output folder that cannot be written, even by root.
  const auto proc = run_cli("view " + workcell("dallara") + " --key patch --out /proc/leeway-view.html");
  EXPECT_EQ(proc.exit_code, 2) << proc.out;
  EXPECT_NE(proc.out.find("/proc/leeway-view.html"), std::string::npos) << proc.out;
  // An output folder that cannot be written.
  fs::create_directory(path("locked"));
  fs::permissions(path("locked"), fs::perms::owner_read | fs::perms::owner_exec);
  const auto locked = run_cli("view " + workcell("dallara") + " --key patch --out " + path("locked/v.html"));
  fs::permissions(path("locked"), fs::perms::owner_all);
  if (::geteuid() != 0) {  // root writes anyway
    EXPECT_EQ(locked.exit_code, 2) << locked.out;
    EXPECT_FALSE(fs::exists(path("locked/v.html")));
  }
  // three.js missing: named, nothing written.
  const auto no_three =
      test::run_program("LEEWAY_THREE_DIR=" + path("nowhere") + " " + std::string(LEEWAY_CLI),
                        "view " + workcell("dallara") + " --key patch --out " + path("v.html"));
  EXPECT_EQ(no_three.exit_code, 2) << no_three.out;
  EXPECT_NE(no_three.out.find("libjs-three"), std::string::npos) << no_three.out;
  EXPECT_FALSE(fs::exists(path("v.html")));
}

// Headless Chromium (Debian's chromium; $LEEWAY_CHROMIUM overrides): a fresh profile per run.
std::string chromium() {
  if (const char* env = std::getenv("LEEWAY_CHROMIUM"); env && *env) return env;
  for (const char* p : {"/usr/bin/chromium", "/usr/bin/chromium-browser"})
    if (fs::exists(p)) return p;
  return "";
}

// Standard output of Chromium opening `page` with the query `query` (its standard error, where it
// logs, is dropped).
std::string browse(const std::string& page, const std::string& query, const std::string& action,
                   const fs::path& profile) {
  const std::string cmd = "timeout 120 " + chromium() +
                          " --headless --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader"
                          " --disable-dev-shm-usage --hide-scrollbars --no-first-run --disable-extensions"
                          " --user-data-dir=" +
                          profile.string() + " --window-size=800,600 " + action + " 'file://" + page + "?" +
                          query + "' 2>/dev/null";
  std::string out;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (!pipe) return out;
  std::array<char, 4096> buf{};
  size_t n = 0;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) out.append(buf.data(), n);
  ::pclose(pipe);
  return out;
}

std::string unescape_html(std::string text) {
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"&lt;", "<"}, {"&gt;", ">"}, {"&quot;", "\""}, {"&#39;", "'"}, {"&amp;", "&"}})
    for (size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
      text.replace(at, from.size(), to);
  return text;
}

// The page's state and errors after it loaded (its <pre id="state"> and <pre id="errors">).
struct PageState {
  json state;
  std::string errors;
  std::string status;
};

PageState page_state(const std::string& page, const std::string& query, const fs::path& profile) {
  const std::string dom = browse(page, query, "--dump-dom", profile);
  PageState s;
  std::smatch m;
  if (std::regex_search(dom, m, std::regex("<pre id=\"state\">([^<]*)</pre>")))
    s.state = json::parse(unescape_html(m[1].str()), nullptr, false);
  if (std::regex_search(dom, m, std::regex("<pre id=\"errors\"[^>]*>([^<]*)</pre>")))
    s.errors = unescape_html(m[1].str());
  if (std::regex_search(dom, m, std::regex("<div id=\"status\"[^>]*>([^<]*)</div>")))
    s.status = unescape_html(m[1].str());
  return s;
}

Image screenshot(const std::string& page, const std::string& query, const fs::path& dir,
                 const std::string& name) {
  const fs::path png = dir / name;
  browse(page, query, "--screenshot=" + png.string(), dir / ("profile-" + name));
  if (!fs::exists(png)) return Image{};
  std::ifstream in(png, std::ios::binary);
  return test::decode_browser_png(
      std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()));
}

long pixels_differing(const Image& a, const Image& b) {
  long n = 0;
  for (size_t i = 0; i + 2 < a.rgb.size() && i + 2 < b.rgb.size(); i += 3)
    if (std::abs(a.rgb[i] - b.rgb[i]) + std::abs(a.rgb[i + 1] - b.rgb[i + 1]) +
            std::abs(a.rgb[i + 2] - b.rgb[i + 2]) >
        24)
      ++n;
  return n;
}

// True when Chromium starts here and runs a page's script with WebGL (a machine without it, or
// whose sandbox or GPU setup stops it, skips the browser test rather than blaming the viewer).
bool chromium_runs(const fs::path& dir) {
  const std::string probe = (dir / "probe.html").string();
  std::ofstream(probe)
      << "<p id=\"out\">no script</p><script>document.getElementById('out').textContent = "
         "document.createElement('canvas').getContext('webgl') ? 'webgl' : 'no webgl';</script>";
  return browse(probe, "", "--dump-dom", dir / "probe-profile").find("<p id=\"out\">webgl</p>") !=
         std::string::npos;
}

TEST_F(CliViewTest, InChromiumTheSlidersStayWithinTheBoundsAndMoveTheRobot) {
  if (chromium().empty()) GTEST_SKIP() << "no chromium (Debian: apt-get install chromium)";
  if (!chromium_runs(dir_.path())) GTEST_SKIP() << chromium() << " does not run a page with WebGL here";
  const auto r =
      run_cli("view " + workcell("dallara") + " --bounds " + bounds_file() + " --out " + path("v.html"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::string page = path("v.html");

  // Loaded without an error, at the stop at or before t = 0.5 s (stops every 1/30 s), the status of
  // the thesis's method.
  const PageState at_one = page_state(page, "t=0.5", dir_.path() / "p1");
  ASSERT_TRUE(at_one.state.is_object()) << "no state: the page did not run";
  EXPECT_EQ(at_one.errors, "");
  EXPECT_TRUE(at_one.state.at("ready").get<bool>());
  EXPECT_LE(at_one.state.at("t").get<double>(), 0.5 + 1e-9);
  EXPECT_GT(at_one.state.at("t").get<double>(), 0.5 - 1.0 / 30 - 1e-9);
  EXPECT_NE(at_one.status.find("Not checked beyond the volume"), std::string::npos) << at_one.status;
  EXPECT_GT(at_one.state.at("solid_boxes").get<int>() + at_one.state.at("faded_boxes").get<int>(), 0);

  // A joint pushed far past its bound stops at the bound at that time, on either side.
  const json j2 = at_one.state.at("joints").at(1);
  const std::string name = j2.at("name");
  const PageState past = page_state(page, "t=0.5&q." + name + "=100", dir_.path() / "p2");
  ASSERT_TRUE(past.state.is_object());
  EXPECT_EQ(past.state.at("joints").at(1).at("value").get<double>(), j2.at("upper").get<double>());
  EXPECT_TRUE(past.state.at("moved").get<bool>());
  const PageState below = page_state(page, "t=0.5&q." + name + "=-100", dir_.path() / "p3");
  ASSERT_TRUE(below.state.is_object());
  EXPECT_EQ(below.state.at("joints").at(1).at("value").get<double>(), j2.at("lower").get<double>());
  EXPECT_EQ(below.errors, "");
  // Not a number leaves the joint at its nominal value.
  const PageState nan = page_state(page, "t=0.5&q." + name + "=oops", dir_.path() / "p4");
  ASSERT_TRUE(nan.state.is_object());
  EXPECT_EQ(nan.state.at("joints").at(1).at("value").get<double>(), j2.at("nominal").get<double>());
  EXPECT_FALSE(nan.state.at("moved").get<bool>());

  // Without bounds a slider stops at its joint's limit (j1 of the IRB 6700: 2.9671 rad in the cell).
  const auto bare = run_cli("view " + workcell("dallara") + " --key patch --out " + path("bare.html"));
  ASSERT_EQ(bare.exit_code, 0) << bare.out;
  const PageState limit = page_state(path("bare.html"), "q.j1=100", dir_.path() / "p5");
  ASSERT_TRUE(limit.state.is_object());
  EXPECT_NEAR(limit.state.at("joints").at(0).at("value").get<double>(), 2.9671, 1e-12);
  EXPECT_EQ(limit.errors, "");

  // The picture is not blank, and the robot's pixels move when a joint moves (volume, ghosts and
  // clearance colours off, so that only the robot can change).
  const Image full = screenshot(page, "t=0.5", dir_.path(), "full.png");
  ASSERT_GT(full.width, 0) << "no screenshot";
  std::set<std::array<unsigned char, 3>> colours;
  for (size_t i = 0; i + 2 < full.rgb.size(); i += 3)
    colours.insert({full.rgb[i], full.rgb[i + 1], full.rgb[i + 2]});
  EXPECT_GT(colours.size(), 50u);
  const std::string plain = "t=0.5&panel=off&volume=off&ghosts=off&clearance=off";
  const Image nominal = screenshot(page, plain, dir_.path(), "nominal.png");
  const json j1 = at_one.state.at("joints").at(0);
  const Image turned = screenshot(
      page,
      plain + "&q." + j1.at("name").get<std::string>() + "=" + std::to_string(j1.at("lower").get<double>()),
      dir_.path(), "turned.png");
  const Image again = screenshot(page, plain, dir_.path(), "again.png");
  ASSERT_EQ(nominal.rgb.size(), turned.rgb.size());
  const long moved = pixels_differing(nominal, turned);
  EXPECT_GT(moved, 200) << "pixels that changed when " << j1.at("name") << " moved to its lower bound";
  EXPECT_LT(pixels_differing(nominal, again), moved / 10) << "the same view twice should look the same";
}

}  // namespace
}  // namespace leeway
