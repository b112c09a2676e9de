// The command-line contract of DESIGN.md: --help, --version, --json on stdout, exit codes,
// one-line errors that name the file or option at fault.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "../common/run_cli.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene {
namespace {

namespace fs = std::filesystem;
using testing::line_count;
using testing::run_cli;
using testing::shell_quote;

// One folder bs_cli_<pid> for the whole process (made once: scratch_dir empties it), removed
// when the test process exits.
fs::path fixture_dir() {
  static const fs::path d = testing::scratch_dir("cli");
  return d;
}

fs::path write(const std::string& name, const std::string& text) {
  const auto p = fixture_dir() / name;
  std::ofstream(p) << text;
  return p;
}

std::string good_trajectory(double t0) {
  std::string s;
  for (int i = 0; i < 20; ++i)
    s += std::to_string(t0 + i * 0.1) + " " + std::to_string(0.1 * i) + " " + std::to_string(0.05 * i * i) + " " +
         std::to_string(i % 3) + " 0 0 0 1\n";
  return s;
}

TEST(Cli, HelpAndVersionExitZero) {
  const auto help = run_cli("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("demo"), std::string::npos);
  EXPECT_NE(help.out.find("eval"), std::string::npos);
  const auto version = run_cli("--version");
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_NE(version.out.find("builtscene"), std::string::npos);
  EXPECT_EQ(run_cli("eval ate --help").exit_code, 0);
}

TEST(Cli, UnknownCommandOrOptionIsUsageError) {
  for (const std::string args : {"no-such-command", "eval ate --no-such-option 1", "", "eval"}) {
    const auto r = run_cli(args);
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_EQ(line_count(r.err), 1) << args << ": " << r.err;
    EXPECT_TRUE(r.out.empty()) << args;
  }
}

TEST(Cli, EvalAteJsonHasContractKeys) {
  const auto gt = write("gt.txt", good_trajectory(0));
  const auto r = run_cli("eval ate --json --gt " + shell_quote(gt) + " --est " + shell_quote(gt));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key : {"rmse", "mean", "median", "max", "pairs", "align"}) EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["pairs"].get<int>(), 20);
  EXPECT_LT(j["rmse"].get<double>(), 1e-9);
}

// A trajectory as a second frame sees it: rotated 90 degrees about z, shifted by (1, 2, 3),
// plus an offset along that frame's x.
std::string in_other_frame(const std::string& tum, double offset_x) {
  std::istringstream in(tum);
  std::string out, line;
  while (std::getline(in, line)) {
    std::istringstream f(line);
    double t, x, y, z;
    f >> t >> x >> y >> z;
    out += std::to_string(t) + " " + std::to_string(-y + 1 + offset_x) + " " + std::to_string(x + 2) + " " +
           std::to_string(z + 3) + " 0 0 0.70710678 0.70710678\n";
  }
  return out;
}

TEST(Cli, EvalAteAlignFromAppliesAnotherRunsAlignmentUnchanged) {
  // Run A (the map's) is exact in the other frame; run B (localization) is 0.1 m off along x
  // everywhere. Fitted on A, B's error is exactly 0.1 m; fitted on B itself, the offset
  // disappears into the alignment.
  const auto gt_a = write("gt_a.txt", good_trajectory(0));
  const auto est_a = write("est_a.txt", in_other_frame(good_trajectory(0), 0));
  std::string gt_b_text;
  for (int i = 0; i < 15; ++i)
    gt_b_text += std::to_string(100 + i * 0.1) + " " + std::to_string(2 - 0.2 * i) + " " + std::to_string(0.03 * i * i) +
                 " 0.5 0 0 0 1\n";
  const auto gt_b = write("gt_b.txt", gt_b_text);
  const auto est_b = write("est_b.txt", in_other_frame(gt_b_text, 0.1));
  const auto fitted = run_cli("eval ate --json --gt " + shell_quote(gt_b) + " --est " + shell_quote(est_b) +
                              " --align-from " + shell_quote(est_a) + " " + shell_quote(gt_a));
  ASSERT_EQ(fitted.exit_code, 0) << fitted.err;
  const auto j = nlohmann::json::parse(fitted.out);
  EXPECT_NEAR(j["rmse"].get<double>(), 0.1, 1e-5);
  EXPECT_NEAR(j["max"].get<double>(), 0.1, 1e-5);
  EXPECT_EQ(j["pairs"].get<int>(), 15);
  EXPECT_LT(j["align_from"]["rmse"].get<double>(), 1e-5);
  const auto self = run_cli("eval ate --json --gt " + shell_quote(gt_b) + " --est " + shell_quote(est_b));
  ASSERT_EQ(self.exit_code, 0) << self.err;
  EXPECT_LT(nlohmann::json::parse(self.out)["rmse"].get<double>(), 1e-5);
  // A missing file of the pair is named.
  const auto missing = run_cli("eval ate --gt " + shell_quote(gt_b) + " --est " + shell_quote(est_b) +
                               " --align-from /nonexistent/map_run.txt " + shell_quote(gt_a));
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_EQ(line_count(missing.err), 1) << missing.err;
  EXPECT_NE(missing.err.find("/nonexistent/map_run.txt"), std::string::npos) << missing.err;
}

TEST(Cli, BadTrajectoryInputExitsTwoWithOneLineNamingTheFile) {
  const auto gt = write("gt_ok.txt", good_trajectory(0));
  struct Case {
    std::string name, content, expect_in_message;
  };
  const std::vector<Case> cases{
      {"empty.txt", "", "empty.txt"},
      {"malformed.txt", "0.0 1 2 3 0 0 0 1\n0.1 1 2 x 0 0 0 1\n", "malformed.txt:2"},
      {"no_overlap.txt", good_trajectory(500), "overlapping"},
  };
  for (const auto& c : cases) {
    const auto est = write(c.name, c.content);
    for (const std::string cmd : {"eval ate", "eval rpe"}) {
      const auto r = run_cli(cmd + " --json --gt " + shell_quote(gt) + " --est " + shell_quote(est));
      EXPECT_EQ(r.exit_code, 2) << cmd << " " << c.name;
      EXPECT_EQ(line_count(r.err), 1) << r.err;
      EXPECT_NE(r.err.find(c.expect_in_message), std::string::npos) << r.err;
      EXPECT_TRUE(r.out.empty()) << "no JSON on failure: " << r.out;
    }
  }
  const auto missing = run_cli("eval ate --gt " + shell_quote(gt) + " --est /nonexistent/est.txt");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("/nonexistent/est.txt"), std::string::npos);
  const auto bad_align = run_cli("eval ate --align affine --gt " + shell_quote(gt) + " --est " + shell_quote(gt));
  EXPECT_EQ(bad_align.exit_code, 2);
  EXPECT_NE(bad_align.err.find("--align"), std::string::npos);
}

TEST(Cli, DemoIntoAFileIsBadInput) {
  const auto file = write("not_a_folder", "x");
  const auto r = run_cli("demo --only none --out " + shell_quote(file / "sub"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(line_count(r.err), 1) << r.err;
}

}  // namespace
}  // namespace builtscene
