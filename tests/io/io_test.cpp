#include <gtest/gtest.h>

#include <fstream>

#include <opencv2/imgcodecs.hpp>

#include "../common/run_cli.hpp"
#include "../common/scratch_dir.hpp"
#include "core/errors.hpp"
#include "io/trajectory.hpp"
#include "io/tum_dataset.hpp"

namespace builtscene {
namespace {

namespace fs = std::filesystem;

// A fresh folder bs_io_<name>_<pid>, removed when the test process exits.
fs::path temp_dir(const std::string& name) { return testing::scratch_dir("io_" + name); }

void write(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

TEST(Association, ClosestPairsFirstOneToOneWithinWindow) {
  // b[1]=1.011 is within 0.02 of a[0]=1.0 and a[1]=1.015; it must go to the closer a[1],
  // leaving a[0] with b[0]=0.99.
  const std::vector<double> a{1.0, 1.015, 2.0, 3.0};
  const std::vector<double> b{0.99, 1.011, 2.5, 3.019};
  const auto pairs = associate_timestamps(a, b, 0.02);
  const std::vector<std::pair<std::size_t, std::size_t>> expected{{0, 0}, {1, 1}, {3, 3}};
  EXPECT_EQ(pairs, expected);
}

TEST(Trajectory, WriteReadRoundTripAndCommaSeparatedInput) {
  const auto d = temp_dir("traj");
  Trajectory t;
  for (int i = 0; i < 10; ++i)
    t.push_back({100.0 + i / 30.0, SE3(Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * i, Eigen::Vector3d::UnitY())),
                                       Eigen::Vector3d(i, -i, 0.5 * i))});
  write_tum_trajectory(d / "t.txt", t);
  const auto r = read_tum_trajectory(d / "t.txt");
  ASSERT_EQ(r.size(), t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    EXPECT_NEAR(r[i].timestamp, t[i].timestamp, 1e-6);
    EXPECT_LT((r[i].pose.matrix() - t[i].pose.matrix()).norm(), 1e-8);
  }
  write(d / "c.txt", "# comment\n1.5,1,2,3,0,0,0,1\n");
  EXPECT_DOUBLE_EQ(read_tum_trajectory(d / "c.txt")[0].pose.translation().y(), 2.0);
}

TEST(Trajectory, MalformedInputNamesFileAndLine) {
  const auto d = temp_dir("traj_bad");
  const std::vector<std::pair<std::string, std::string>> cases{
      {"short.txt", "# header\n1 2 3 4 0 0 0 1\n2 1 2 3 0 0\n"},
      {"nan.txt", "1 nan 0 0 0 0 0 1\n"},
      {"quat.txt", "1 0 0 0 0 0 0 2\n"},
      {"extra.txt", "1 0 0 0 0 0 0 1 9\n"},
  };
  for (const auto& [name, text] : cases) {
    write(d / name, text);
    try {
      read_tum_trajectory(d / name);
      ADD_FAILURE() << name << ": no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
  try {
    read_tum_trajectory(d / "short.txt");
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("short.txt:3:"), std::string::npos) << e.what();
  }
  write(d / "empty.txt", "# nothing\n");
  EXPECT_THROW(read_tum_trajectory(d / "empty.txt"), InputError);
  EXPECT_THROW(read_tum_trajectory(d / "absent.txt"), InputError);
}

fs::path tiny_dataset(const std::string& name, int depth_type = CV_16UC1, int depth_cols = 8) {
  const auto d = temp_dir(name);
  fs::create_directories(d / "rgb");
  fs::create_directories(d / "depth");
  write(d / "camera.yaml",
        "%YAML:1.0\nCamera.fx: 10\nCamera.fy: 10\nCamera.cx: 4\nCamera.cy: 3\nCamera.width: 8\nCamera.height: 6\n"
        "DepthMapFactor: 5000.0\n");
  cv::Mat rgb(6, 8, CV_8UC3, cv::Scalar(10, 20, 30));
  cv::Mat depth(6, depth_cols, depth_type, cv::Scalar(0));
  if (depth_type == CV_16UC1) depth.at<std::uint16_t>(2, 3) = 12345;
  cv::imwrite((d / "rgb/1.png").string(), rgb);
  cv::imwrite((d / "depth/1.png").string(), depth);
  write(d / "rgb.txt", "# colour\n1.000 rgb/1.png\n5.000 rgb/1.png\n");
  write(d / "depth.txt", "1.010 depth/1.png\n");
  return d;
}

TEST(TumDataset, AssociatesAndScalesDepth) {
  const auto d = tiny_dataset("ds_ok");
  const auto ds = TumDataset::open(d);
  ASSERT_EQ(ds.size(), 1u);  // the 5.0 colour frame has no depth within 0.02 s
  EXPECT_DOUBLE_EQ(ds.entry(0).depth_timestamp, 1.010);
  const cv::Mat depth = ds.load_depth(0);
  EXPECT_EQ(depth.type(), CV_32F);
  EXPECT_NEAR(depth.at<float>(2, 3), 12345.0 / 5000.0, 1e-6);
  EXPECT_EQ(depth.at<float>(0, 0), 0.0f);
  EXPECT_EQ(ds.load_rgb(0).at<cv::Vec3b>(0, 0), cv::Vec3b(10, 20, 30));
}

TEST(TumDataset, WrongDepthTypeOrSizeIsNamed) {
  const auto d8 = tiny_dataset("ds_8bit", CV_8UC1);
  try {
    TumDataset::open(d8).load_depth(0);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("16-bit"), std::string::npos);
  }
  const auto dsz = tiny_dataset("ds_size", CV_16UC1, 9);
  EXPECT_THROW(TumDataset::open(dsz).load_depth(0), InputError);
  const auto dn = tiny_dataset("ds_noassoc");
  write(dn / "depth.txt", "9.0 depth/1.png\n");
  EXPECT_THROW(TumDataset::open(dn), InputError);
  EXPECT_THROW(TumDataset::open("/nonexistent/dataset"), InputError);
}

TEST(TumDataset, RealSevenScenesKitchenOpens) {
  const auto dir = testing::shared_data() / "7scenes-kitchen";
  if (!fs::exists(dir)) GTEST_SKIP() << "../shared/data/7scenes-kitchen is absent";
  const auto ds = TumDataset::open(dir);
  EXPECT_EQ(ds.size(), 1000u);
  const cv::Mat depth = ds.load_depth(0);
  EXPECT_EQ(depth.cols, 640);
  double lo, hi;
  cv::minMaxLoc(depth, &lo, &hi);
  EXPECT_GE(lo, 0.0);
  EXPECT_GT(hi, 0.5);  // a kitchen seen from a hand-held Kinect: metres of depth
  EXPECT_LT(hi, 10.0);
  EXPECT_EQ(ds.groundtruth().size(), 1000u);
}

}  // namespace
}  // namespace builtscene
