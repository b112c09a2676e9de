// The command's contract: bad input -> exit 2 with one line naming the option or path; --json
// keys; byte-identical output for the same seed.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <memory>

#include <nlohmann/json.hpp>

#include "../common/shell_quote.hpp"
#include "rgbd_test_util.hpp"

namespace {

using builtscene::testing::shell_quote;

struct RunResult {
  int code;
  std::string out;
};

RunResult run(const std::string& args, bool stdout_only = false) {
  const std::string cmd = shell_quote(BUILTSCENE_BINARY) + " " + args + (stdout_only ? " 2>/dev/null" : " 2>&1");
  std::unique_ptr<FILE, int (*)(FILE*)> p(popen(cmd.c_str(), "r"), pclose);
  std::string out;
  std::array<char, 4096> buf;
  while (std::fgets(buf.data(), buf.size(), p.get())) out += buf.data();
  const int status = pclose(p.release());
  return {WEXITSTATUS(status), out};
}

}  // namespace

TEST(RgbdCli, BadInputExitsTwoNamingTheCulprit) {
  const auto dir = synth_test::temp_dir("cli_bad");
  auto r = run("synth rgbd --scene moon-base --out " + shell_quote(dir));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--scene"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("moon-base"), std::string::npos) << r.out;
  r = run("synth rgbd --scene lab-room --frames 0 --out " + shell_quote(dir));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--frames"), std::string::npos) << r.out;
  r = run("synth rgbd --scene lab-room --frames -5 --out " + shell_quote(dir));
  EXPECT_EQ(r.code, 2);
  r = run("synth rgbd --scene lab-room --loops 0 --motion robot --out " + shell_quote(dir));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--loops"), std::string::npos) << r.out;
  r = run("synth rgbd --scene lab-room --motion flying --out " + shell_quote(dir));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--motion"), std::string::npos) << r.out;
  r = run("synth rgbd --scene lab-room --exposure-ms 50 --out " + shell_quote(dir));  // longer than a frame
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--exposure-ms"), std::string::npos) << r.out;
  r = run("synth rgbd --scene lab-room --light-fade 0 --out " + shell_quote(dir));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--light-fade"), std::string::npos) << r.out;
  // A regular file where the folder should be, and a folder under it.
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "file") << "x";
  r = run("synth rgbd --scene lab-room --frames 2 --out " + shell_quote(dir / "file" / "sub"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find((dir / "file").string()), std::string::npos) << r.out;
  std::filesystem::remove_all(dir);
}

TEST(RgbdCli, JsonSummaryAndDeterminism) {
  const auto a = synth_test::temp_dir("cli_a"), b = synth_test::temp_dir("cli_b");
  const std::string args = " synth rgbd --scene demo --frames 3 --seed 5 --noise kinect --json --out ";
  const RunResult ra = run(args + shell_quote(a), true), rb = run(args + shell_quote(b), true);
  ASSERT_EQ(ra.code, 0) << ra.out;
  ASSERT_EQ(rb.code, 0) << rb.out;
  const auto j = nlohmann::json::parse(ra.out);  // stdout carries exactly one JSON object
  EXPECT_EQ(j["frames"], 3);
  for (const char* k : {"seconds", "fps", "stage_ms", "valid_depth_fraction"}) EXPECT_TRUE(j.contains(k)) << k;
  for (const char* k : {"render", "noise", "encode"}) EXPECT_TRUE(j["stage_ms"].contains(k)) << k;
  for (const char* f : {"rgb.txt", "depth.txt", "groundtruth.txt", "camera.yaml", "markers.csv", "truth_map.pgm", "truth_map.yaml",
                        "scene.json", "rgb/000002.png", "depth/000002.png"}) {
    auto read = [](const std::filesystem::path& p) {
      std::ifstream f(p, std::ios::binary);
      return std::string(std::istreambuf_iterator<char>(f), {});
    };
    ASSERT_TRUE(std::filesystem::exists(a / f)) << f;
    EXPECT_EQ(read(a / f), read(b / f)) << f << " differs between two runs with the same seed";
  }
  std::filesystem::remove_all(a);
  std::filesystem::remove_all(b);
}
