#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include <opencv2/imgcodecs.hpp>

#include "../common/scratch_dir.hpp"
#include "../ogm/analytic_depth.hpp"
#include "core/errors.hpp"
#include "nav/points_of_interest.hpp"
#include "nav/region.hpp"
#include "nav/region_cloud_update.hpp"

namespace builtscene {
namespace {

namespace fs = std::filesystem;

TEST(Region, RectangleAndLShapedPolygon) {
  const Region r = Region::parse("4,3,1,1");
  EXPECT_TRUE(r.contains({2, 2}));
  EXPECT_TRUE(r.contains({1, 1}));  // corner: boundary counts
  EXPECT_FALSE(r.contains({0.99, 2}));
  EXPECT_DOUBLE_EQ(r.area(), 6.0);
  const Region l = Region::parse("0,0, 4,0, 4,1, 1,1, 1,3, 0,3");  // an L
  EXPECT_DOUBLE_EQ(l.area(), 6.0);
  EXPECT_TRUE(l.contains({0.5, 2.5}));
  EXPECT_TRUE(l.contains({3.5, 0.5}));
  EXPECT_FALSE(l.contains({2, 2}));  // the L's missing corner
  EXPECT_THROW(Region::parse("1,2,3"), InputError);
  EXPECT_THROW(Region::parse("1,1,1,5"), InputError);
  EXPECT_THROW(Region::parse("a,b,c,d"), InputError);
}

TEST(PoiTrigger, FiresOncePerVisitDespiteBoundaryNoise) {
  PoiTrigger t({{"door", 5, 0, 1.0}, {"desk", 0, 5, 0.5}});
  std::vector<std::string> fired;
  std::size_t frame = 0;
  auto drive = [&](double x0, double x1, double jitter) {
    for (int i = 0; i <= 100; ++i) {
      const double x = x0 + (x1 - x0) * i / 100.0;
      const double y = jitter * ((i % 2) ? 1 : -1);
      for (const auto& e : t.update(frame * 0.1, frame, {x, y, 0})) fired.push_back(e.poi);
      ++frame;
    }
  };
  drive(0, 10, 0.0);  // through the door's radius: one event
  drive(10, 0, 0.0);  // back through it: a second visit
  EXPECT_EQ(fired, (std::vector<std::string>{"door", "door"}));
  fired.clear();
  // Hovering on the radius (4.0 +- 0.03 m from the door at x = 5) within the 0.1 m
  // hysteresis: one event for the whole hover.
  for (int i = 0; i < 50; ++i)
    for (const auto& e : t.update(0, 0, {4.0 + ((i % 2) ? -0.03 : 0.03), 0, 0})) fired.push_back(e.poi);
  EXPECT_EQ(fired.size(), 1u);
}

TEST(PointsOfInterest, CsvErrorsNameFileAndLine) {
  const auto d = testing::scratch_dir("poi");
  std::ofstream(d / "ok.csv") << "name,x,y,radius\ndoor,1,2,0.5\n";
  EXPECT_EQ(read_points_of_interest(d / "ok.csv").size(), 1u);
  std::ofstream(d / "bad.csv") << "name,x,y,radius\ndoor,1,2,0.5\nwin,1,x,0.5\n";
  try {
    read_points_of_interest(d / "bad.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.csv:3"), std::string::npos) << e.what();
  }
  std::ofstream(d / "neg.csv") << "door,1,2,-1\n";
  EXPECT_THROW(read_points_of_interest(d / "neg.csv"), InputError);
  std::ofstream(d / "dup.csv") << "door,1,2,1\ndoor,3,2,1\n";
  EXPECT_THROW(read_points_of_interest(d / "dup.csv"), InputError);
}

TEST(PointCloud, PlyRoundTripAndVoxelMeans) {
  PointCloud c;
  // Two voxels of 0.1 m: three points in the first, one in the second.
  c.push_back({{0.01f, 0.01f, 0.01f}, {10, 20, 30}});
  c.push_back({{0.03f, 0.05f, 0.07f}, {20, 40, 60}});
  c.push_back({{0.05f, 0.03f, 0.01f}, {30, 60, 90}});
  c.push_back({{0.25f, 0.01f, 0.01f}, {1, 2, 3}});
  const PointCloud v = voxel_downsample(c, 0.1);
  ASSERT_EQ(v.size(), 2u);
  EXPECT_NEAR(v[0].position.x(), 0.03f, 1e-6);
  EXPECT_NEAR(v[0].position.y(), 0.03f, 1e-6);
  EXPECT_EQ(v[0].rgb[1], 40);
  const auto d = testing::scratch_dir("ply");
  write_ply(d / "c.ply", c);
  EXPECT_EQ(fs::file_size(d / "c.ply") - c.size() * 15, fs::file_size(d / "c.ply") - 60);
  const PointCloud r = read_ply(d / "c.ply");
  ASSERT_EQ(r.size(), c.size());
  for (std::size_t i = 0; i < c.size(); ++i) {
    EXPECT_EQ(r[i].position, c[i].position);
    EXPECT_EQ(r[i].rgb, c[i].rgb);
  }
  std::ifstream in(d / "c.ply", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(d / "t.ply", std::ios::binary) << bytes.substr(0, bytes.size() - 7);
  EXPECT_THROW(read_ply(d / "t.ply"), InputError);
  std::ofstream(d / "a.ply") << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n";
  EXPECT_FLOAT_EQ(read_ply(d / "a.ply")[0].position.z(), 3.0f);
}

// A room 8 x 4 m with walls and a box; frames at x = 1 (left half) and x = 6 (right half).
fs::path write_room_dataset(std::vector<SE3>& poses, std::vector<testing::Box>& boxes) {
  boxes = {{{-0.1, -2.1, 0}, {8.1, -2.0, 2.5}}, {{-0.1, 2.0, 0}, {8.1, 2.1, 2.5}}, {{-0.2, -2.1, 0}, {-0.1, 2.1, 2.5}},
           {{8.0, -2.1, 0}, {8.1, 2.1, 2.5}},   {{-1, -3, -0.1}, {9, 3, 0.0}},      {{3.5, -0.5, 0}, {4.5, 0.5, 1.0}}};
  const auto cam = testing::kinect_camera();
  const auto d = testing::scratch_dir("cloud_ds");
  fs::create_directories(d / "rgb");
  fs::create_directories(d / "depth");
  std::ofstream(d / "camera.yaml") << "Camera.fx: 525\nCamera.fy: 525\nCamera.cx: 319.5\nCamera.cy: 239.5\nCamera.width: 640\nCamera.height: 480\nDepthMapFactor: 5000\n";
  std::ofstream rgb_list(d / "rgb.txt"), depth_list(d / "depth.txt");
  poses.clear();
  int i = 0;
  for (double x : {1.0, 1.0, 6.0, 6.0})
    for (double yaw : {0.0, 3.14159}) {
      const SE3 T = testing::level_camera(x + 0.3 * (i % 2), 0.0, 1.0, yaw + 0.2 * (i % 3));
      poses.push_back(T);
      const cv::Mat depth = testing::render_depth(cam, T, boxes);
      cv::Mat d16;
      depth.convertTo(d16, CV_16U, 5000.0);
      const std::string name = std::to_string(i) + ".png";
      cv::imwrite((d / "depth" / name).string(), d16);
      cv::imwrite((d / "rgb" / name).string(), cv::Mat(480, 640, CV_8UC3, cv::Scalar(i * 20, 100, 200)));
      rgb_list << i << ".0 rgb/" << name << "\n";
      depth_list << i << ".0 depth/" << name << "\n";
      ++i;
    }
  return d;
}

double distance_to_surfaces(const Eigen::Vector3f& p, const std::vector<testing::Box>& boxes) {
  double best = 1e9;
  for (const auto& b : boxes) {
    // Distance to a box's surface: outside, the distance to the box; inside, to the nearest face.
    const Eigen::Vector3d q = p.cast<double>();
    const Eigen::Vector3d c = q.cwiseMax(b.lo).cwiseMin(b.hi);
    double d = (q - c).norm();
    if (d == 0) d = std::min({q.x() - b.lo.x(), b.hi.x() - q.x(), q.y() - b.lo.y(), b.hi.y() - q.y(), q.z() - b.lo.z(), b.hi.z() - q.z()});
    best = std::min(best, d);
  }
  return best;
}

TEST(RegionCloudUpdate, ReplacesOnlyTheRegionWithPointsOnTheSurfaces) {
  std::vector<SE3> poses;
  std::vector<testing::Box> boxes;
  const auto dir = write_room_dataset(poses, boxes);
  const TumDataset ds = TumDataset::open(dir);
  std::vector<PosedFrame> frames;
  for (std::size_t i = 0; i < poses.size(); ++i) frames.push_back({i, poses[i]});  // z-up world = ground
  // An "old" cloud: a grid of points everywhere, shifted 0.5 m up (stale).
  PointCloud old;
  for (double x = 0; x < 8; x += 0.25)
    for (double y = -2; y < 2; y += 0.25) old.push_back({Eigen::Vector3f(x, y, 0.5f), {1, 1, 1}});
  const Region left = Region::rectangle(0, -2, 3, 2);
  CloudBuildOptions o;
  o.voxel = 0.05;
  const auto r = update_cloud_in_region(ds, frames, left, &old, o);
  EXPECT_EQ(r.frames_outside_region, 4u);  // the frames at x = 6
  EXPECT_GT(r.frames_integrated, 0u);
  EXPECT_GT(r.points_added, 300u);
  std::size_t old_inside = 0;
  for (const auto& p : old) old_inside += left.contains({p.position.x(), p.position.y()});
  EXPECT_EQ(r.points_removed, old_inside);
  EXPECT_EQ(r.points_kept, old.size() - old_inside);
  for (std::size_t i = 0; i < r.points_kept; ++i) EXPECT_FALSE(left.contains({r.cloud[i].position.x(), r.cloud[i].position.y()}));
  std::size_t off = 0;
  for (std::size_t i = r.points_kept; i < r.cloud.size(); ++i) {
    const auto& p = r.cloud[i];
    EXPECT_TRUE(left.contains({p.position.x(), p.position.y()}));
    off += distance_to_surfaces(p.position, boxes) > o.voxel;  // voxel means lie within a voxel of the surface
  }
  EXPECT_EQ(off, 0u);
}

}  // namespace
}  // namespace builtscene
