// The bad-input corpus: tests/bad_input/manifest.json lists command lines over the cells,
// parameter, bounds and path files of tests/bad_input/ with the exit code and a fragment of the
// message each must give; every entry is one test, run in a fresh temporary folder.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "test_util.hpp"

namespace leeway {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kCorpus = std::string(LEEWAY_TEST_DATA_DIR) + "/../bad_input";

std::vector<json> corpus_cases() {
  std::ifstream in(kCorpus + "/manifest.json");
  const json manifest = json::parse(in);
  return manifest.at("cases").get<std::vector<json>>();
}

using test::read_text;

std::string expand(std::string text, const std::string& tmp) {
  for (const auto& [key, value] : {std::pair<std::string, std::string>{"{corpus}", kCorpus}, {"{tmp}", tmp}})
    for (size_t at = text.find(key); at != std::string::npos; at = text.find(key, at + value.size()))
      text.replace(at, key.size(), value);
  return text;
}

class BadInputCorpus : public ::testing::TestWithParam<json> {};

TEST_P(BadInputCorpus, ExitCodeAndMessage) {
  const json& c = GetParam();
  test::TempDir dir;
  const std::string tmp = dir.path().string();
  if (c.contains("fifo")) {
    ASSERT_EQ(::mkfifo(expand(c.at("fifo"), tmp).c_str(), 0600), 0);
  }
  if (c.contains("copy")) {
    // One [from, to] pair or a list of them; folders of `to` are made.
    const json pairs = c.at("copy")[0].is_array() ? c.at("copy") : json::array({c.at("copy")});
    for (const auto& pair : pairs) {
      const fs::path to = expand(pair[1], tmp);
      fs::create_directories(to.parent_path());
      fs::copy_file(expand(pair[0], tmp), to);
    }
  }
  if (c.contains("symlink")) {
    ASSERT_EQ(::symlink(expand(c.at("symlink")[0], tmp).c_str(), expand(c.at("symlink")[1], tmp).c_str()), 0);
  }
  const std::string unchanged = c.contains("unchanged") ? expand(c.at("unchanged"), tmp) : "";
  const std::string before = unchanged.empty() ? "" : read_text(unchanged);

  const std::string program = c.value("program", std::string("leeway")) == "leeway-tune"
                                  ? (fs::path(LEEWAY_CLI).parent_path() / "leeway-tune").string()
                                  : std::string(LEEWAY_CLI);
  // Standard error to a file, so that an entry may redirect standard output ("> /dev/full").
  const std::string err = tmp + "/stderr.txt";
  const test::CliResult r =
      test::run_program("cd " + tmp + " && " + program, expand(c.at("args"), tmp) + " 2>" + err + " #");
  const std::string stderr_text = read_text(err);
  const std::string all = r.out + stderr_text;
  const std::string name = c.at("name");
  EXPECT_EQ(r.exit_code, c.at("exit").get<int>()) << name << ":\n" << all;
  const std::string message = expand(c.at("message"), tmp);
  EXPECT_NE(all.find(message), std::string::npos) << name << ": expected '" << message << "' in:\n" << all;
  EXPECT_EQ(all.find("internal error"), std::string::npos) << name << ":\n" << all;
  if (c.contains("stderr_lines")) {
    EXPECT_EQ(std::count(stderr_text.begin(), stderr_text.end(), '\n'), c.at("stderr_lines").get<int>())
        << name << ":\n"
        << stderr_text;
  }
  if (c.contains("not_created")) {
    EXPECT_FALSE(fs::exists(expand(c.at("not_created"), tmp))) << name;
  }
  if (!unchanged.empty()) {
    EXPECT_EQ(read_text(unchanged), before) << name << ": " << unchanged << " changed";
  }
  if (c.contains("symlink")) {
    // The link is still there, still pointing where it did.
    const fs::path link = expand(c.at("symlink")[1], tmp);
    EXPECT_TRUE(fs::is_symlink(fs::symlink_status(link))) << name << ": " << link << " is no longer a link";
    EXPECT_EQ(fs::read_symlink(link).string(), expand(c.at("symlink")[0], tmp)) << name;
  }
}

INSTANTIATE_TEST_SUITE_P(Manifest, BadInputCorpus, ::testing::ValuesIn(corpus_cases()),
                         [](const ::testing::TestParamInfo<json>& entry) {
                           return entry.param.at("name").get<std::string>();
                         });

}  // namespace
}  // namespace leeway
