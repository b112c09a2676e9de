// `builtscene slam` on bad input: a short real sequence copied to a temporary folder and then
// damaged (a corrupt colour image, a depth image of the wrong type, a timestamp out of order,
// a blank frame, a missing depth file). Every defect is counted and reported; nothing crashes.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "../common/run_cli.hpp"
#include "../common/scratch_dir.hpp"

namespace {

namespace fs = std::filesystem;
const fs::path kKitchen = fs::path(BUILTSCENE_SOURCE_DIR) / "../shared/data/7scenes-kitchen";

using builtscene::testing::run_cli;
using builtscene::testing::shell_quote;

std::vector<std::string> lines_of(const fs::path& f) {
  std::ifstream in(f);
  std::vector<std::string> v;
  for (std::string l; std::getline(in, l);)
    if (!l.empty() && l[0] != '#') v.push_back(l);
  return v;
}

class SlamCommand : public ::testing::Test {
 protected:
  fs::path dir;
  void SetUp() override {
    dir = builtscene::testing::scratch_dir("slam_cmd");
    fs::remove_all(dir);
  }
  void TearDown() override { fs::remove_all(dir); }

  // The first n frames of the kitchen, with its camera.yaml and ground truth.
  void copy_kitchen(std::size_t n) {
    fs::create_directories(dir / "rgb");
    fs::create_directories(dir / "depth");
    fs::copy_file(kKitchen / "camera.yaml", dir / "camera.yaml");
    for (const char* list : {"rgb.txt", "depth.txt"}) {
      std::ofstream out(dir / list);
      const auto l = lines_of(kKitchen / list);
      for (std::size_t i = 0; i < n && i < l.size(); ++i) {
        out << l[i] << "\n";
        std::istringstream s(l[i]);
        double t;
        std::string file;
        s >> t >> file;
        fs::copy_file(kKitchen / file, dir / file);
      }
    }
  }
  std::string file_of(const char* list, std::size_t i) {
    std::istringstream s(lines_of(dir / list).at(i));
    double t;
    std::string file;
    s >> t >> file;
    return file;
  }
};

TEST_F(SlamCommand, BadInputIsCountedNotFatal) {
  if (!fs::exists(kKitchen / "rgb.txt")) GTEST_SKIP() << "7scenes-kitchen not found at " << kKitchen;
  copy_kitchen(30);
  // Frame 10: corrupt colour image.
  std::ofstream(dir / file_of("rgb.txt", 10), std::ios::trunc) << "not a jpeg";
  // Frame 12: depth saved as 8-bit.
  cv::imwrite((dir / file_of("depth.txt", 12)).string(), cv::Mat(480, 640, CV_8UC1, cv::Scalar(40)));
  // Frame 14: blank grey image (no features).
  cv::imwrite((dir / file_of("rgb.txt", 14)).string(), cv::Mat(480, 640, CV_8UC3, cv::Scalar(128, 128, 128)));
  // Frame 16: depth file missing.
  fs::remove(dir / file_of("depth.txt", 16));
  // Frame 20's timestamp moved before frame 19's (depth.txt keeps the association).
  {
    auto rgb = lines_of(dir / "rgb.txt");
    auto depth = lines_of(dir / "depth.txt");
    const std::string old_t = rgb[20].substr(0, rgb[20].find(' '));
    const std::string new_t = std::to_string(std::stod(rgb[18].substr(0, rgb[18].find(' '))) + 0.001);
    rgb[20] = new_t + rgb[20].substr(rgb[20].find(' '));
    depth[20] = new_t + depth[20].substr(depth[20].find(' '));
    std::ofstream r(dir / "rgb.txt"), d(dir / "depth.txt");
    for (auto& l : rgb) r << l << "\n";
    for (auto& l : depth) d << l << "\n";
  }

  const auto r =
      run_cli("slam --dataset " + shell_quote(dir) + " --trajectory " + shell_quote(dir / "traj.txt") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["frames"], 30);
  EXPECT_EQ(j["bad_input"]["unreadable_rgb"], 1);
  EXPECT_EQ(j["bad_input"]["bad_depth"], 2);  // 8-bit and missing
  EXPECT_EQ(j["bad_input"]["timestamp_out_of_order"], 1);
  EXPECT_EQ(j["bad_input"]["no_features"], 1);
  // 30 frames: 2 skipped (corrupt, out of order). The blank frame has no features: it is
  // either lost or carried by the depth-odometry bridge (its depth image is intact).
  EXPECT_EQ(j["processed_frames"], 28);
  EXPECT_GE(j["tracked_frames"].get<int>(), 25);
  EXPECT_GE(j["lost_frames"].get<int>() + j["depth_odometry_frames"].get<int>(), 1);
  EXPECT_EQ(j["tracked_frames"].get<int>() + j["lost_frames"].get<int>(), 28);
  for (const char* key : {"keyframes", "map_points", "fps", "stage_ms"}) EXPECT_TRUE(j.contains(key)) << key;
  for (const char* stage : {"extraction", "tracking", "local_map"}) EXPECT_TRUE(j["stage_ms"].contains(stage)) << stage;
  EXPECT_EQ(lines_of(dir / "traj.txt").size(), j["tracked_frames"].get<std::size_t>());
}

TEST_F(SlamCommand, SynchronousMappingTracksAndMaps) {
  if (!fs::exists(kKitchen / "rgb.txt")) GTEST_SKIP() << "7scenes-kitchen not found at " << kKitchen;
  copy_kitchen(20);
  const auto r = run_cli("slam --dataset " + shell_quote(dir) + " --trajectory " + shell_quote(dir / "traj.txt") +
                     " --keyframes " + shell_quote(dir / "kf.txt") + " --sync-mapping --max-frames 15 --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["frames"], 15);
  EXPECT_EQ(j["tracked_frames"], 15);
  EXPECT_GE(j["keyframes"].get<int>(), 1);
  EXPECT_GE(j["local_mapping"]["keyframes_processed"].get<int>(), 1);
  EXPECT_EQ(lines_of(dir / "kf.txt").size(), j["keyframes"].get<std::size_t>());
}

TEST_F(SlamCommand, MissingDatasetIsUsageError) {
  const auto r =
      run_cli("slam --dataset " + shell_quote(dir / "nope") + " --trajectory " + shell_quote(dir / "t.txt"));
  EXPECT_EQ(r.exit_code, 2);
}

TEST_F(SlamCommand, BadPriorAndLinkValuesAreUsageErrorsNamingTheFlag) {
  // Checked before the dataset is opened (this one does not exist): the flag is the fault.
  const std::string base =
      "slam --dataset " + shell_quote(dir / "nope") + " --trajectory " + shell_quote(dir / "t.txt");
  for (const auto& [args, flag] : {std::pair{" --motion-prior -1", "--motion-prior"},
                                   std::pair{" --motion-prior 1 --motion-prior-deg nan", "--motion-prior-deg"},
                                   std::pair{" --depth-links --depth-link-weight 0", "--depth-link-weight"},
                                   std::pair{" --depth-planes --depth-plane-weight 0", "--depth-plane-weight"},
                                   std::pair{" --depth-planes --depth-plane-weight nan", "--depth-plane-weight"},
                                   std::pair{" --depth-prior -0.5", "--depth-prior"},
                                   std::pair{" --depth-prior nan", "--depth-prior"},
                                   std::pair{" --depth-prior-below -3", "--depth-prior-below"},
                                   std::pair{" --min-parallax-sigmas -1", "--min-parallax-sigmas"},
                                   std::pair{" --min-parallax-sigmas nan", "--min-parallax-sigmas"},
                                   std::pair{" --descriptor saft --saft-handover-check", "--saft-handover-check"},
                                   std::pair{" --descriptor saft --saft-mode discrete --saft-handover-check",
                                             "--saft-handover-check"},
                                   std::pair{" --descriptor saft --saft-calibrate-decision", "--saft-calibrate-decision"}}) {
    const auto r = run_cli(base + args);
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_NE(r.err.find(flag), std::string::npos) << args << ": " << r.err;
    EXPECT_FALSE(fs::exists(dir / "t.txt"));
  }
}

TEST_F(SlamCommand, AllBlankFramesNeverInitializeButDoNotCrash) {
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  std::ofstream(dir / "camera.yaml") << "%YAML:1.0\nCamera.fx: 525.0\nCamera.fy: 525.0\nCamera.cx: 319.5\nCamera.cy: 239.5\n"
                                        "Camera.k1: 0.0\nCamera.k2: 0.0\nCamera.p1: 0.0\nCamera.p2: 0.0\n"
                                        "Camera.width: 640\nCamera.height: 480\nDepthMapFactor: 5000.0\n";
  std::ofstream rgb(dir / "rgb.txt"), depth(dir / "depth.txt");
  for (int i = 0; i < 5; ++i) {
    const std::string t = std::to_string(1.0 + i / 30.0);
    cv::imwrite((dir / ("rgb/" + std::to_string(i) + ".png")).string(), cv::Mat(480, 640, CV_8UC3, cv::Scalar::all(90)));
    cv::imwrite((dir / ("depth/" + std::to_string(i) + ".png")).string(), cv::Mat(480, 640, CV_16UC1, cv::Scalar(5000)));
    rgb << t << " rgb/" << i << ".png\n";
    depth << t << " depth/" << i << ".png\n";
  }
  rgb.close();
  depth.close();
  const auto r =
      run_cli("slam --dataset " + shell_quote(dir) + " --trajectory " + shell_quote(dir / "traj.txt") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["tracked_frames"], 0);
  EXPECT_EQ(j["lost_frames"], 5);
  EXPECT_EQ(j["bad_input"]["no_features"], 5);
  EXPECT_EQ(j["keyframes"], 0);
}

}  // namespace
