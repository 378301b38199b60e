// Defects that the bad-input corpus (bad_input_test.cpp) cannot show from a command line:
// the JSON reader's limits, output files and signals, thread creation failures, allocation
// failures, MuJoCo warnings from worker threads, sweep rows and leeway-tune's log.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <new>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "cli/support.hpp"
#include "core/json_io.hpp"
#include "core/parallel.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/mujoco_util.hpp"
#include "leeway/core/params.hpp"
#include "leeway/core/scene.hpp"
#include "stl_util.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

namespace fs = std::filesystem;

const std::string kCorpus = std::string(LEEWAY_TEST_DATA_DIR) + "/../bad_input";

using test::read_text;

using test::error_of;

// ------------------------------------------------------------------------------------ JSON input

TEST(JsonInput, DeepNestingIsRefusedWithoutRecursion) {
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  EXPECT_NE(error_of([&] { detail::parse_json_text(deep, "deep.json"); }).find("nested deeper than 64"),
            std::string::npos);
  const std::string ok = std::string(64, '[') + std::string(64, ']');
  EXPECT_NO_THROW(detail::parse_json_text(ok, "ok.json"));
}

TEST(JsonInput, DuplicateKeysAreRefusedNamingTheKey) {
  EXPECT_EQ(error_of([] { detail::parse_json_text(R"({"a": {"b": 1, "b": 2}})", "f.json"); }),
            "f.json: JSON key 'b' appears twice in one object");
  // The same key in two objects is fine.
  EXPECT_NO_THROW(
      detail::parse_json_text(R"({"a": {"b": 1}, "c": {"b": 2}, "d": [{"b": 1}, {"b": 2}]})", "f"));
}

TEST(JsonInput, NumbersBeyondDoubleAreRefused) {
  EXPECT_NE(
      error_of([] {
        detail::parse_json_text(R"({"volume": {"h_max": 1e400}})", "p.json");
      }).find("p.json: malformed JSON: [json.exception.out_of_range.406] number overflow parsing '1e400'"),
      std::string::npos);
  EXPECT_NE(error_of([] { read_params(kCorpus + "/params/overflow.json"); }).find("overflow.json"),
            std::string::npos);
}

TEST(JsonInput, FoldersAndFifosAreRefusedBeforeOpening) {
  test::TempDir dir;
  EXPECT_EQ(error_of([&] { detail::read_json_file(dir.path().string(), "bounds file"); }),
            dir.path().string() + ": the bounds file is a folder, not a regular file");
  const std::string fifo = (dir.path() / "f.json").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(error_of([&] { detail::read_json_file(fifo, "path file"); }),
            fifo + ": the path file is a FIFO (named pipe), not a regular file");  // and no hang
  EXPECT_EQ(error_of([&] { load_model_file(fifo); }),
            fifo + ": the file is a FIFO (named pipe), not a regular file");
}

// ---------------------------------------------------------------------------------- output files

TEST(OutputFiles, NonRegularTargetsAndInputsAreRefused) {
  test::TempDir dir;
  EXPECT_NE(error_of([] { write_file_atomic("/dev/null", "x"); }).find("is a device, not a regular file"),
            std::string::npos);
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  const std::string input = dir.write("cell.xml", "<mujoco/>");
  EXPECT_NE(error_of([&] {
              require_outputs({{(dir.path() / "." / "cell.xml").string(), "--out", {}}}, {input});
            }).find("is the input file"),
            std::string::npos);
  EXPECT_NO_THROW(require_outputs({{(dir.path() / "new.json").string(), "--out", {}}}, {input}));
  EXPECT_EQ(error_of([] { write_file_atomic("", "x"); }), "the output file name is empty");
}

TEST(OutputFiles, WriteFileAtomicReplacesAndLeavesNoTemporary) {
  test::TempDir dir;
  const std::string path = (dir.path() / "out.json").string();
  write_file_atomic(path, "one");
  write_file_atomic(path, "two");
  EXPECT_EQ(read_text(path), "two");
  int files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir.path())) ++files;
  EXPECT_EQ(files, 1);
}

// A process ended by SIGTERM while an output file is being written leaves no temporary file
// behind: the child creates one (as write_file_atomic does), reports its name and waits.
TEST(OutputFiles, SigtermRemovesTheTemporaryFile) {
  test::TempDir dir;
  const std::string target = (dir.path() / "out.json").string();
  int names[2];
  ASSERT_EQ(::pipe(names), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    install_temp_file_cleanup();
    try {
      TempFile tmp(target);
      tmp.write("text");
      const std::string line = tmp.path() + "\n";
      if (::write(names[1], line.data(), line.size()) != static_cast<ssize_t>(line.size())) ::_exit(3);
      ::pause();
    } catch (...) {
      ::_exit(4);
    }
    ::_exit(5);
  }
  ::close(names[1]);
  std::string tmp;
  char c = 0;
  while (::read(names[0], &c, 1) == 1 && c != '\n') tmp += c;
  ::close(names[0]);
  ASSERT_FALSE(tmp.empty());
  ASSERT_TRUE(fs::is_regular_file(tmp)) << tmp;
  EXPECT_EQ(fs::path(tmp).parent_path(), dir.path());
  ::kill(child, SIGTERM);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << status;
  EXPECT_FALSE(fs::exists(tmp));
  EXPECT_FALSE(fs::exists(target));
}

// The reported attack on each writing program: a link to a victim file planted at the temporary
// name leeway used to use, .NAME.tmpPID (the shell execs the program, so $$ is its PID). The victim
// keeps its content, the link stays, the output is a regular file.
TEST(OutputFiles, ProgramsLeaveALinkAtTheOldTemporaryNameAlone) {
  const std::string tune = (fs::path(LEEWAY_CLI).parent_path() / "leeway-tune").string();
  const std::string ok = kCorpus + "/cells/ok.xml";
  const std::vector<std::pair<std::string, std::string>> runs = {
      {"b.json", std::string(LEEWAY_CLI) + " bounds " + ok + " --from a --to b --safety none --out b.json"},
      {"v.xml",
       std::string(LEEWAY_CLI) + " bounds " + ok + " --from a --to b --safety none --export-mjcf v.xml"},
      {"p.json", std::string(LEEWAY_CLI) + " plan " + ok + " --from a --to b --out p.json"},
      {"t.json", tune + " --case " + ok + ":a:b --budget-evals 2 --no-summary --threads 1 --out t.json"},
  };
  for (const auto& [out, command] : runs) {
    test::TempDir dir;
    const std::string victim = dir.write("victim", "keep\n");
    const auto r = test::run_program("cd " + dir.path().string() + " && bash -c",
                                     "'ln -s " + victim + " ." + out + ".tmp$$; exec " + command + "'");
    ASSERT_EQ(r.exit_code, 0) << command << "\n" << r.out;
    EXPECT_EQ(read_text(victim), "keep\n") << command;
    EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(dir.path() / out))) << command;
    int links = 0;
    for (const auto& e : fs::directory_iterator(dir.path()))
      if (fs::is_symlink(e.symlink_status())) {
        ++links;
        EXPECT_EQ(fs::read_symlink(e.path()).string(), victim);
      }
    EXPECT_EQ(links, 1) << command;
  }
}

// A cell whose obstacle is a mesh: `plan --out` and `bounds --out` may not replace the STL file, nor
// `import-urdf --out` the mesh its own URDF names.
TEST(OutputFiles, MeshesTheRunReadsAreNotReplaced) {
  test::TempDir dir;
  fs::create_directories(dir.path() / "assets");
  const std::string stl = (dir.path() / "assets" / "cube.stl").string();
  test::write_binary_stl(stl, test::cuboid({-0.1, -0.1, -0.1}, {0.1, 0.1, 0.1}));
  std::string cell = read_text(kCorpus + "/cells/ok.xml");
  cell.replace(cell.find("<worldbody>"), 0, R"(<compiler meshdir="assets"/>
  <asset><mesh name="cube" file="cube.stl"/></asset>
  )");
  cell.replace(
      cell.find("</worldbody>"), 0,
      R"(  <geom name="crate" type="mesh" mesh="cube" pos="-0.6 0.6 0.1" contype="0" conaffinity="1"/>
  )");
  const std::string cell_path = dir.write("cell.xml", cell);
  const std::string before = read_text(stl);
  for (const std::string& command : {"plan " + cell_path + " --from a --to b --out " + stl,
                                     "bounds " + cell_path + " --from a --to b --out " + stl}) {
    const auto r = test::run_cli(command);
    EXPECT_EQ(r.exit_code, 2) << r.out;
    EXPECT_NE(r.out.find("--out " + stl + ": the output file is the input file " + dir.path().string() +
                         "/assets/cube.stl"),
              std::string::npos)
        << r.out;
    EXPECT_EQ(read_text(stl), before);
  }
  const std::string urdf = dir.write("arm.urdf", R"(<robot name="arm">
  <link name="base"/>
  <link name="tool0"><collision><geometry><mesh filename="assets/cube.stl"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="tool0"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>)");
  const auto r = test::run_cli("import-urdf " + urdf + " --out " + stl);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("--out " + stl + ": the output file is the input file"), std::string::npos) << r.out;
  EXPECT_EQ(read_text(stl), before);
}

// new-cell may not replace a file its robot fragment includes (resolved from the cell's folder).
TEST(OutputFiles, NewCellDoesNotReplaceWhatTheRobotIncludes) {
  test::TempDir dir;
  std::string robot = read_text(kCorpus + "/robots/one_link.xml");
  const std::string marker =
      "<mujoco><geom name=\"marker\" type=\"sphere\" size=\"0.01\" contype=\"0\" "
      "conaffinity=\"0\"/></mujoco>\n";
  const std::string part = dir.write("part.xml", marker);
  robot.replace(robot.find("  <body name=\"base\">"), 0, "  <include file=\"part.xml\"/>\n");
  const std::string robot_path = dir.write("robot.xml", robot);
  const auto r = test::run_cli("new-cell --robot " + robot_path + " --out " + part);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find(part + ": the output file is the input file"), std::string::npos) << r.out;
  EXPECT_EQ(read_text(part), marker);
}

// ------------------------------------------------------------------------- threads and memory

// Under an address-space limit that leaves no room for more thread stacks, parallel_for runs every
// item on the threads it could create instead of terminating the process.
TEST(Threads, CreationFailureFallsBackToFewerThreads) {
#ifdef LEEWAY_TEST_ASAN
  // Under ASan an address-space limit fails ASan's own fake-stack mappings for a new thread, which
  // abort the process before std::thread can report anything.
  GTEST_SKIP() << "an address-space limit cannot be tested under AddressSanitizer";
#endif
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    long pages = 0;
    std::ifstream("/proc/self/statm") >> pages;
    const rlim_t limit =
        static_cast<rlim_t>(pages) * static_cast<rlim_t>(::sysconf(_SC_PAGESIZE)) + (64u << 20);
    const rlimit rl{limit, limit};
    if (::setrlimit(RLIMIT_AS, &rl) != 0) ::_exit(3);
    std::atomic<int> done{0};
    try {
      detail::parallel_for(1000, 64, [&] { return [&](int) { ++done; }; });
    } catch (...) {
      ::_exit(4);
    }
    ::_exit(done == 1000 ? 0 : 5);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status)) << "the child was killed by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

TEST(Errors, AllocationFailureIsExit2WithAMessage) {
  testing::internal::CaptureStderr();
  const int code = cli::run_reporting_errors("leeway", []() -> int { throw std::bad_alloc(); });
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, kExitBadInput);
  EXPECT_NE(err.find("leeway: error: out of memory"), std::string::npos) << err;
  EXPECT_EQ(err.find("internal error"), std::string::npos) << err;
}

// ------------------------------------------------------------------------------ MuJoCo warnings

std::atomic<int> g_warnings{0};
void count_warning(const char*) { ++g_warnings; }

// MuJoCo formats warning text in one process-wide buffer: a full contact buffer in mj_collision on
// two worker threads at once was a data race. No warning may fire from a collision check.
TEST(MujocoWarnings, NoneFromCollisionChecksOnTwoThreads) {
  install_mujoco_error_handlers();
  SceneOptions options;
  options.checker = CollisionChecker::kMujoco;  // mj_collision itself, with nconmax="1"
  const Scene scene = Scene::load(kCorpus + "/cells/full_contacts.xml", options);
  auto* const saved = mju_user_warning;
  g_warnings = 0;
  mju_user_warning = count_warning;
  std::atomic<int> hits{0};
  auto work = [&] {
    RobotState state(scene);
    for (int i = 0; i < 200; ++i) {
      Eigen::VectorXd q(1);
      q << 0.001 * i;
      hits += state.in_collision(q) ? 1 : 0;
    }
  };
  std::thread a(work), b(work);
  a.join();
  b.join();
  mju_user_warning = saved;
  EXPECT_EQ(hits, 400);  // a full contact buffer still answers "in collision"
  EXPECT_EQ(g_warnings, 0);
}

// --------------------------------------------------------------------------- programs end to end

TEST(Sweep, CsvRowsAreWrittenAsTheyFinish) {
  test::TempDir dir;
  const std::string csv = (dir.path() / "t.csv").string();
  const auto r = test::run_cli("sweep " + kCorpus + "/cells/ok.xml --from a --to b --max-cells 100,200" +
                               " --windows 2 --samples 5 --threads 1 --csv " + csv);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::string text = read_text(csv);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 3) << text;
  EXPECT_EQ(text.rfind("max_cells,", 0), 0u) << text;
}

TEST(Mjb, CellsWorkInCheckAndBounds) {
  test::TempDir dir;
  const std::string mjb = (dir.path() / "ok.mjb").string();
  {
    const ModelPtr m = load_model_file(kCorpus + "/cells/ok.xml");
    mj_saveModel(m.get(), mjb.c_str(), nullptr, 0);
  }
  const auto check = test::run_cli("check " + mjb);
  EXPECT_EQ(check.exit_code, 0) << check.out;
  const auto bounds = test::run_cli("bounds " + mjb + " --from a --to b --threads 2");
  EXPECT_EQ(bounds.exit_code, 0) << bounds.out;
}

// Defect 9: `bounds` searched the cell's text for "</worldbody>" to place its volume body, so a
// comment holding that tag after the world body made a valid cell fail. The cell is now compiled
// once and the volume model built from the compiled scene: the comment changes nothing.
TEST(ValidCells, AWorldBodyEndTagInACommentIsJustAComment) {
  test::TempDir dir;
  std::string text = read_text(kCorpus + "/cells/ok.xml");
  const size_t end = text.find("</worldbody>");
  ASSERT_NE(end, std::string::npos);
  text.insert(end + std::string("</worldbody>").size(), "\n  <!-- the world body ends with </worldbody> -->");
  const std::string commented = dir.write("commented.xml", text);
  const std::string plain_out = (dir.path() / "plain.json").string(),
                    commented_out = (dir.path() / "commented.json").string();
  const auto plain = test::run_cli("bounds " + kCorpus +
                                   "/cells/ok.xml --from a --to b --safety none --json --out " + plain_out);
  const auto with_comment =
      test::run_cli("bounds " + commented + " --from a --to b --safety none --json --out " + commented_out);
  ASSERT_EQ(plain.exit_code, 0) << plain.out;
  ASSERT_EQ(with_comment.exit_code, 0) << with_comment.out;
  const auto a = nlohmann::json::parse(read_text(plain_out)),
             b = nlohmann::json::parse(read_text(commented_out));
  EXPECT_EQ(a["waypoints"], b["waypoints"]);
  EXPECT_EQ(a["boxes"], b["boxes"]);
}

// Two runs with one --log: the second is refused before any work while the first holds the log's
// lock (flock(1) holds it here), and the log keeps the first run's rows.
TEST(Tune, ALogLockedByAnotherRunIsRefused) {
  test::TempDir dir;
  const std::string tune = (fs::path(LEEWAY_CLI).parent_path() / "leeway-tune").string();
  const std::string log = dir.write("log.csv", "the first run's rows\n");
  const auto r = test::run_program("flock " + log + " " + tune,
                                   "--case " + kCorpus + "/cells/ok.xml:a:b --budget-evals 1 --log " + log +
                                       " --out " + (dir.path() / "t.json").string());
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("--log " + log + ": the file is locked by another process writing it"),
            std::string::npos)
      << r.out;
  EXPECT_EQ(read_text(log), "the first run's rows\n");
  EXPECT_FALSE(fs::exists(dir.path() / "t.json"));
}

// SIGINT during leeway-tune's calibration keeps an existing --log as it was.
TEST(Tune, InterruptedCalibrationKeepsTheLog) {
  test::TempDir dir;
  const std::string tune = (fs::path(LEEWAY_CLI).parent_path() / "leeway-tune").string();
  const std::string log = dir.write("log.csv", "an earlier run's rows\n");
  const std::string script = dir.write(
      "run.sh", "cd " + dir.path().string() + "\n" + tune + " --case " + test::workcell("dallara") +
                    ":home:patch --budget-evals 1 --log log.csv --out tuned.json 2>err.txt &\n"
                    "pid=$!\n"
                    "for i in $(seq 1 600); do grep -q calibrating err.txt && break; sleep 0.05; done\n"
                    "kill -INT $pid\nwait $pid\necho \"exit=$?\"\ncat err.txt\n");
  const auto r = test::run_program("sh", script);
  if (r.out.find("interrupted before the first evaluation") == std::string::npos)
    GTEST_SKIP() << "the calibration ended before the signal:\n" << r.out;
  EXPECT_NE(r.out.find("exit=130"), std::string::npos) << r.out;
  EXPECT_EQ(read_text(log), "an earlier run's rows\n");
  EXPECT_FALSE(fs::exists(dir.path() / "tuned.json"));
}

// Runs `argv` with standard output a pipe whose reading end is closed before the program starts
// (as `leeway check --json | head -c 1` once head has gone) and standard error into `err`; SIGPIPE
// starts at its default action. Returns the wait status, -1 when the program could not be started.
int run_into_closed_pipe(const std::vector<std::string>& argv, const std::string& err) {
  int fds[2];
  if (::pipe(fds) != 0) return -1;
  ::close(fds[0]);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
  posix_spawn_file_actions_addopen(&actions, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t defaults;
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGPIPE);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGDEF);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = ::posix_spawn(&pid, args[0], &actions, &attr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  ::close(fds[1]);
  if (rc != 0) return -1;
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
}

// A closed standard output is the documented exit 2 with one line on standard error, not death by
// SIGPIPE (exit 141 in a shell), for leeway and leeway-tune.
TEST(ClosedPipe, StandardOutputClosedIsExitTwo) {
  test::TempDir dir;
  const std::string err = (dir.path() / "err.txt").string();
  const std::string tune = (fs::path(LEEWAY_CLI).parent_path() / "leeway-tune").string();
  for (const auto& argv : std::vector<std::vector<std::string>>{
           {LEEWAY_CLI, "check", kCorpus + "/cells/ok.xml", "--json"}, {tune, "--help"}}) {
    const int status = run_into_closed_pipe(argv, err);
    ASSERT_NE(status, -1) << argv[0];
    EXPECT_FALSE(WIFSIGNALED(status)) << argv[0] << " died by signal " << WTERMSIG(status);
    ASSERT_TRUE(WIFEXITED(status)) << argv[0];
    EXPECT_EQ(WEXITSTATUS(status), 2) << argv[0];
    const std::string text = read_text(err);
    EXPECT_NE(text.find("error: standard output: writing failed (Broken pipe)"), std::string::npos)
        << argv[0] << ": " << text;
    EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
  }
}

// A cell's <option> must not blind the checks: with contacts or constraints disabled, an override
// margin of -0.1 m or predefined pairs only, MuJoCo would report no contact for a keyframe whose
// link lies 20 cm inside a table. leeway resets those options in its model: the keyframe collides,
// `check` fails on it and says which option it overrode, and RobotState::in_collision (what the path
// check, the planner, CF and the sampled mode ask) sees the contact.
TEST(CellOptions, NoOptionBlindsTheChecks) {
  const char* options[] = {
      R"(<option><flag contact="disable"/></option>)",
      R"(<option><flag constraint="disable"/></option>)",
      R"(<option o_margin="-0.1"><flag override="enable"/></option>)",
      R"(<option collision="predefined"/>)",
  };
  for (const char* option : options) {
    SCOPED_TRACE(option);
    test::TempDir dir;
    // The link (z 0.45 .. 0.55) at j1 = 1.57 lies over y 0 .. 1; the table's top is at z = 0.65.
    std::string xml =
        test::one_link_cell(R"(<geom name="table" type="box" size="0.3 0.3 0.325" pos="0 0.6 0.325"/>)",
                            R"(<key name="home" qpos="0"/><key name="low" qpos="1.57"/>)");
    xml.replace(xml.find("<worldbody>"), 11, std::string(option) + "<worldbody>");
    const Scene scene = Scene::load(dir.write("cell.xml", xml));
    ASSERT_EQ(scene.overridden_options().size(), 1u);
    RobotState state(scene);
    EXPECT_TRUE(state.in_collision(Eigen::VectorXd::Constant(1, 1.57)));
    EXPECT_FALSE(state.in_collision(Eigen::VectorXd::Constant(1, 0.0)));
    const auto check = test::run_cli("check " + dir.path().string() + "/cell.xml");
    EXPECT_EQ(check.exit_code, 1) << check.out;
    EXPECT_NE(check.out.find("the cell's option"), std::string::npos) << check.out;
  }
}

}  // namespace
}  // namespace leeway
