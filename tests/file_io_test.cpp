// The output-path policy (file_io.hpp): temporary files that never follow or reuse a name someone
// else placed, outputs refused when they are links, inputs of the run or each other, and streamed
// outputs locked against a second writer.
#include "leeway/core/file_io.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <set>
#include <string>
#include <vector>

#include "leeway/core/error.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

using test::read_text;

using test::error_of;

std::vector<std::string> entries(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

mode_t mode_of(const fs::path& p) {
  struct stat st {};
  ::lstat(p.c_str(), &st);
  return st.st_mode & 07777;
}

// ------------------------------------------------------------------------------ temporary files

TEST(TempFileTest, IsANewHiddenRegularFileBesideTheTargetWithAnUnpredictableName) {
  test::TempDir dir;
  const std::string target = (dir.path() / "out.json").string();
  std::set<std::string> names;
  for (int i = 0; i < 20; ++i) {
    TempFile tmp(target);
    const fs::path p(tmp.path());
    EXPECT_EQ(p.parent_path(), dir.path());
    EXPECT_EQ(p.filename().string().rfind(".out.json.", 0), 0u) << p;
    EXPECT_EQ(p.filename().string().size(), std::string(".out.json.").size() + 12) << p;
    EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(p)));
    // Twelve random hex digits, not the PID (another user could plant a link at a name derived from
    // it). The digits may happen to contain the PID's: only the old ".tmpPID" form is ruled out.
    const std::string suffix = p.filename().string().substr(std::string(".out.json.").size());
    EXPECT_EQ(suffix.find_first_not_of("0123456789abcdef"), std::string::npos) << p;
    EXPECT_NE(suffix, "tmp" + std::to_string(::getpid())) << p;
    names.insert(p.filename().string());
  }
  EXPECT_EQ(names.size(), 20u);
  EXPECT_TRUE(entries(dir.path()).empty());  // each removed by its destructor
}

TEST(TempFileTest, CommitRenamesOverTheTargetAndLeavesNothingElse) {
  test::TempDir dir;
  const fs::path target = dir.path() / "out.json";
  {
    TempFile tmp(target.string());
    tmp.write("new");
    tmp.commit();
  }
  EXPECT_EQ(read_text(target), "new");
  EXPECT_EQ(entries(dir.path()), std::vector<std::string>{"out.json"});
}

TEST(TempFileTest, MissingFolderIsAnInputErrorNamingTheTarget) {
  test::TempDir dir;
  const std::string target = (dir.path() / "no" / "out.json").string();
  EXPECT_THAT(error_of([&] { TempFile tmp(target); }), HasSubstr(target + ": cannot write the output file"));
}

// ------------------------------------------------------------------------- write_file_atomic

// The reported attack: a link planted at the temporary name leeway used to use (.NAME.tmpPID).
// The victim keeps its content, the link stays a link to it, the output is a regular file.
TEST(WriteFileAtomicTest, ALinkAtTheOldTemporaryNameIsLeftAlone) {
  test::TempDir dir;
  const fs::path victim = dir.path() / "victim";
  std::ofstream(victim) << "keep\n";
  const fs::path link = dir.path() / (".b.json.tmp" + std::to_string(::getpid()));
  fs::create_symlink(victim, link);
  const fs::path out = dir.path() / "b.json";
  write_file_atomic(out.string(), "{}\n");
  EXPECT_EQ(read_text(victim), "keep\n");
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(link)));
  EXPECT_EQ(fs::read_symlink(link), victim);
  EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(out)));
  EXPECT_EQ(read_text(out), "{}\n");
}

TEST(WriteFileAtomicTest, ATargetThatIsALinkIsRefusedAndNeitherItNorItsFileChanges) {
  test::TempDir dir;
  const fs::path victim = dir.path() / "victim";
  std::ofstream(victim) << "keep\n";
  const fs::path out = dir.path() / "b.json";
  fs::create_symlink(victim, out);
  EXPECT_THAT(error_of([&] { write_file_atomic(out.string(), "x"); }),
              HasSubstr(out.string() + ": the output file is a symbolic link"));
  EXPECT_EQ(read_text(victim), "keep\n");
  EXPECT_EQ(fs::read_symlink(out), victim);
  EXPECT_EQ(entries(dir.path()), (std::vector<std::string>{"b.json", "victim"}));
}

TEST(WriteFileAtomicTest, AReplacedFileKeepsItsPermissions) {
  test::TempDir dir;
  const fs::path out = dir.path() / "private.json";
  std::ofstream(out) << "old";
  fs::permissions(out, fs::perms::owner_read | fs::perms::owner_write);
  write_file_atomic(out.string(), "new");
  EXPECT_EQ(read_text(out), "new");
  EXPECT_EQ(mode_of(out), 0600u);
  // A new file: 0644 less the umask.
  const mode_t mask = ::umask(022);
  ::umask(mask);
  write_file_atomic((dir.path() / "new.json").string(), "x");
  EXPECT_EQ(mode_of(dir.path() / "new.json"), 0644u & ~mask);
}

// ---------------------------------------------------------------------------- require_outputs

TEST(RequireOutputsTest, AnInputByAnotherNameOrAHardLinkIsRefused) {
  test::TempDir dir;
  fs::create_directories(dir.path() / "robots");
  fs::create_directories(dir.path() / "cells");
  const std::string robot = dir.write("robots/arm.xml", "<mujoco/>");
  const std::string via = (dir.path() / "cells" / ".." / "robots" / "arm.xml").string();
  EXPECT_THAT(error_of([&] {
                require_outputs({{robot, "--out", {}}}, {"", via});
              }),
              HasSubstr("--out " + robot + ": the output file is the input file " + via));
  // A folder reached through a link.
  fs::create_directory_symlink(dir.path() / "robots", dir.path() / "r");
  EXPECT_THAT(error_of([&] {
                require_outputs({{(dir.path() / "r/arm.xml").string(), "--out", {}}}, {robot});
              }),
              HasSubstr("is the input file"));
  // A hard link: the same inode.
  fs::create_hard_link(robot, dir.path() / "hard.xml");
  EXPECT_THAT(
      error_of([&] {
        require_outputs({{(dir.path() / "hard.xml").string(), "--log", {}}}, {robot});
      }),
      HasSubstr("--log " + (dir.path() / "hard.xml").string() + ": the output file is the input file"));
  EXPECT_NO_THROW(require_outputs({{(dir.path() / "new.xml").string(), "--out", {}}}, {robot}));
}

TEST(RequireOutputsTest, TwoOutputsNamingOneFileAreRefused) {
  test::TempDir dir;
  const std::string a = (dir.path() / "t.json").string();
  const std::string b = (dir.path() / "." / "t.json").string();
  EXPECT_EQ(error_of([&] {
              require_outputs({{a, "--out", {}}, {"", "--report", {}}, {b, "--log", {}}}, {});
            }),
            "--out and --log name the same file " + a + "; one output would be lost");
  EXPECT_NO_THROW(require_outputs({{a, "--out", {}}, {(dir.path() / "u.json").string(), "--log", {}}}, {}));
  EXPECT_TRUE(entries(dir.path()).empty());
}

TEST(RequireOutputsTest, LinksFoldersAndMissingFoldersAreRefused) {
  test::TempDir dir;
  const fs::path dangling = dir.path() / "dangling.json";
  fs::create_symlink(dir.path() / "nowhere", dangling);
  EXPECT_THAT(error_of([&] {
                require_outputs({{dangling.string(), "--out", {}}}, {});
              }),
              HasSubstr("the output file is a symbolic link"));
  EXPECT_FALSE(fs::exists(dir.path() / "nowhere"));
  EXPECT_THAT(error_of([&] {
                require_outputs({{dir.path().string(), "--out", {}}}, {});
              }),
              HasSubstr("the output file is a folder"));
  EXPECT_THAT(error_of([&] {
                require_outputs({{(dir.path() / "no/x.json").string(), "--out", {}}}, {});
              }),
              HasSubstr("missing or not writable"));
  EXPECT_THAT(error_of([&] {
                require_outputs({{(dir.path() / "x.txt").string(), "--out", {".png"}}}, {});
              }),
              HasSubstr("the file name must end in .png"));
}

// ---------------------------------------------------------------------------- StreamingOutput

TEST(StreamingOutputTest, ASecondWriterIsRefusedWhileTheFirstHoldsTheLock) {
  test::TempDir dir;
  const std::string log = (dir.path() / "log.csv").string();
  StreamingOutput first(log, "--log");
  first.truncate();
  first.stream() << "a,b\n" << std::flush;
  EXPECT_THAT(error_of([&] { StreamingOutput second(log, "--log"); }),
              HasSubstr("--log " + log + ": the file is locked by another process writing it"));
  first.stream() << "1,2\n" << std::flush;
  EXPECT_EQ(read_text(log), "a,b\n1,2\n");  // no rows of the refused writer, none lost
  first = StreamingOutput();                // closed: the lock is released
  EXPECT_NO_THROW(StreamingOutput again(log, "--log"));
}

TEST(StreamingOutputTest, TheOldContentStaysUntilTruncateAndANewFileUnusedIsRemoved) {
  test::TempDir dir;
  const std::string log = dir.write("log.csv", "an earlier run\n");
  { StreamingOutput kept(log, "--log"); }
  EXPECT_EQ(read_text(log), "an earlier run\n");
  const fs::path fresh = dir.path() / "fresh.csv";
  { StreamingOutput unused(fresh.string(), "--csv"); }
  EXPECT_FALSE(fs::exists(fresh));
  {
    StreamingOutput used(log, "--log");
    used.truncate();
    used.stream() << "row\n";
  }
  EXPECT_EQ(read_text(log), "row\n");
}

TEST(StreamingOutputTest, ALinkIsRefusedAndItsFileKeptAsItWas) {
  test::TempDir dir;
  const fs::path victim = dir.path() / "victim";
  std::ofstream(victim) << "keep\n";
  const fs::path log = dir.path() / "log.csv";
  fs::create_symlink(victim, log);
  EXPECT_THAT(error_of([&] { StreamingOutput s(log.string(), "--log"); }),
              HasSubstr("--log " + log.string() + ": the output file is a symbolic link"));
  EXPECT_EQ(read_text(victim), "keep\n");
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(log)));
  EXPECT_THAT(error_of([&] { StreamingOutput s("/dev/null", "--csv"); }),
              HasSubstr("--csv /dev/null: the output file is a device"));
}

}  // namespace
}  // namespace leeway
