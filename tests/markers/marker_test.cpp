#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <random>
#include <regex>

#include <opencv2/imgcodecs.hpp>

#include "../common/kinect_camera.hpp"
#include "../common/run_cli.hpp"
#include "../common/scratch_dir.hpp"
#include "core/errors.hpp"
#include "markers/marker_measurements.hpp"

namespace builtscene {
namespace {

namespace fs = std::filesystem;

PinholeCamera camera() { return testing::kinect_camera(); }

// Renders the tag's bit image on a plane with pose T_cg (tag frame: x right, y up, z out of
// the face), 4 x 4 supersampling per pixel; background grey 128. `size` is the side of the
// black border square (AprilTag's convention); total_width cells include the white border.
cv::Mat render(const cv::Mat& bits, int width_at_border, double size, const SE3& T_cg, const PinholeCamera& cam,
               std::array<Eigen::Vector2d, 4>* corners = nullptr) {
  const double cell = size / width_at_border;
  const int W = bits.cols;
  const SE3 T_gc = T_cg.inverse();
  cv::Mat img(cam.height, cam.width, CV_8UC1);
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      double acc = 0;
      for (int sv = 0; sv < 4; ++sv)
        for (int su = 0; su < 4; ++su) {
          const Eigen::Vector3d ray((u - 0.375 + 0.25 * su - cam.cx) / cam.fx, (v - 0.375 + 0.25 * sv - cam.cy) / cam.fy, 1.0);
          // Intersect the ray with the tag plane z_g = 0.
          const Eigen::Vector3d o = T_gc.translation(), d = T_gc.rotation() * ray;
          double val = 128;
          if (std::abs(d.z()) > 1e-9) {
            const double s = -o.z() / d.z();
            if (s > 0) {
              const Eigen::Vector3d p = o + s * d;
              const int c = static_cast<int>(std::floor(p.x() / cell + W / 2.0));
              const int r = static_cast<int>(std::floor(W / 2.0 - p.y() / cell));
              if (c >= 0 && r >= 0 && c < W && r < W) val = bits.at<std::uint8_t>(r, c);
            }
          }
          acc += val;
        }
      img.at<std::uint8_t>(v, u) = static_cast<std::uint8_t>(std::lround(acc / 16));
    }
  if (corners) {
    const auto obj = tag_corners(size);
    for (std::size_t k = 0; k < 4; ++k) (*corners)[k] = cam.project(T_cg * obj[k]);
  }
  return img;
}

// Exact z-depth of the tag's plane (infinite plane: the background is the same plane).
cv::Mat plane_depth(const SE3& T_cg, const PinholeCamera& cam) {
  cv::Mat depth(cam.height, cam.width, CV_32F);
  const SE3 T_gc = T_cg.inverse();
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector3d ray((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
      const Eigen::Vector3d o = T_gc.translation(), d = T_gc.rotation() * ray;
      depth.at<float>(v, u) = static_cast<float>(-o.z() / d.z());
    }
  return depth;
}

SE3 look_at_tag(double distance, double tilt_deg, double yaw_deg) {
  // Camera looking at the tag's centre from `distance`, the tag turned by tilt about its x axis
  // and yaw about the camera's optical axis.
  const double t = tilt_deg * std::numbers::pi / 180, y = yaw_deg * std::numbers::pi / 180;
  // A tag facing the camera has z towards the camera (camera z is forward): rotate 180 deg about x.
  const Eigen::Matrix3d facing = Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Matrix3d R = Eigen::AngleAxisd(y, Eigen::Vector3d::UnitZ()).toRotationMatrix() * facing *
                            Eigen::AngleAxisd(t, Eigen::Vector3d::UnitX()).toRotationMatrix();
  return SE3(R, Eigen::Vector3d(0.05, -0.03, distance));
}

TEST(TagPose, RenderedTagPoseWithinOneCentimetreAndOneDegree) {
  const AprilTagDetector detector;
  const cv::Mat bits = detector.render_tag(7);
  const auto cam = camera();
  const double size = 0.16;
  for (double dist : {1.0, 2.0, 3.0})
    for (double tilt : {0.0, 35.0}) {
      const SE3 truth = look_at_tag(dist, tilt, 20.0);
      std::array<Eigen::Vector2d, 4> corners;
      const cv::Mat img = render(bits, 8, size, truth, cam, &corners);
      const auto dets = detector.detect(img);
      ASSERT_EQ(dets.size(), 1u) << dist << " " << tilt;
      EXPECT_EQ(dets[0].id, 7);
      for (std::size_t k = 0; k < 4; ++k)
        EXPECT_LT((dets[0].corners[k] - corners[k]).norm(), 0.5) << "corner " << k << " at " << dist << " m";
      // RGB-D (the generated worlds' case): within 1 cm and 1 degree.
      const auto pose = estimate_tag_pose(dets[0], size, cam, plane_depth(truth, cam));
      ASSERT_TRUE(pose);
      EXPECT_TRUE(pose->depth_refined);
      EXPECT_LT((pose->T_cg.translation() - truth.translation()).norm(), 0.01) << dist << " m, tilt " << tilt;
      const double angle = Eigen::AngleAxisd(pose->T_cg.rotation().conjugate() * truth.rotation()).angle();
      EXPECT_LT(angle * 180 / std::numbers::pi, 1.0) << dist << " m, tilt " << tilt;
      const double true_view = std::acos(truth.rotation_matrix().col(2).dot(-truth.translation().normalized())) * 180 / std::numbers::pi;
      EXPECT_NEAR(pose->viewing_angle_deg, true_view, 1.0);
      // Corners only: the position still within 2 cm; the tilt of a small fronto-parallel tag
      // is poorly conditioned (up to a few degrees at 3 m), which is why depth is used.
      const auto mono = estimate_tag_pose(dets[0], size, cam);
      ASSERT_TRUE(mono);
      EXPECT_LT((mono->T_cg.translation() - truth.translation()).norm(), 0.02) << dist << " m, tilt " << tilt;
    }
}

TEST(TagPose, DepthRefinementRemovesTheRangeError) {
  // A tag printed 5 % larger than declared: the monocular range is 5 % short; the depth image
  // (exact) corrects it.
  const AprilTagDetector detector;
  const auto cam = camera();
  const SE3 truth = look_at_tag(2.5, 20.0, 0.0);
  const cv::Mat img = render(detector.render_tag(3), 8, 0.21, truth, cam);
  const cv::Mat depth = plane_depth(truth, cam);
  const auto dets = detector.detect(img);
  ASSERT_EQ(dets.size(), 1u);
  const auto mono = estimate_tag_pose(dets[0], 0.20, cam);
  const auto fused = estimate_tag_pose(dets[0], 0.20, cam, depth);
  ASSERT_TRUE(mono && fused);
  EXPECT_GT((mono->T_cg.translation() - truth.translation()).norm(), 0.08);
  EXPECT_TRUE(fused->depth_refined);
  EXPECT_LT((fused->T_cg.translation() - truth.translation()).norm(), 0.01);
}

// The listed corners of the real photographs: "id, (x y), (x y), (x y), (x y)".
std::vector<std::array<Eigen::Vector2d, 4>> read_listed(const fs::path& p) {
  std::vector<std::array<Eigen::Vector2d, 4>> out;
  std::ifstream in(p);
  std::string line;
  const std::regex num(R"([-+]?[0-9]*\.?[0-9]+)");
  while (std::getline(in, line)) {
    std::vector<double> v;
    for (auto it = std::sregex_iterator(line.begin(), line.end(), num); it != std::sregex_iterator(); ++it) v.push_back(std::stod(it->str()));
    if (v.size() != 9) continue;
    out.push_back({Eigen::Vector2d(v[1], v[2]), Eigen::Vector2d(v[3], v[4]), Eigen::Vector2d(v[5], v[6]), Eigen::Vector2d(v[7], v[8])});
  }
  return out;
}

// Largest corner distance under the best cyclic correspondence (either direction).
double corner_error(const std::array<Eigen::Vector2d, 4>& a, const std::array<Eigen::Vector2d, 4>& b) {
  double best = 1e9;
  for (int dir : {1, -1})
    for (int s = 0; s < 4; ++s) {
      double worst = 0;
      for (int k = 0; k < 4; ++k) worst = std::max(worst, (a[static_cast<std::size_t>(k)] - b[static_cast<std::size_t>(((s + dir * k) % 4 + 4) % 4)]).norm());
      best = std::min(best, worst);
    }
  return best;
}

TEST(AprilTagReal, CornersWithinOnePointFivePixelsOfTheListedOnes) {
  const auto dir = testing::shared_data() / "apriltag-real";
  if (!fs::exists(dir)) GTEST_SKIP() << "../shared/data/apriltag-real is absent";
  AprilTagOptions o;
  o.upsample = 2;  // several tags here are only 15-20 px wide
  const AprilTagDetector detector(o);
  int matched = 0, listed_total = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".jpg") continue;
    const auto listed = read_listed(fs::path(entry.path()).replace_extension(".txt"));
    const auto dets = detector.detect(cv::imread(entry.path().string(), cv::IMREAD_GRAYSCALE));
    listed_total += static_cast<int>(listed.size());
    for (const auto& l : listed) {
      double best = 1e9;
      for (const auto& d : dets) best = std::min(best, corner_error(l, d.corners));
      if (best >= 1.5) std::cerr << "not within 1.5 px: " << entry.path().filename() << " quad at " << l[0].transpose() << " (" << best << " px)\n";
      matched += best < 1.5;
    }
  }
  // 44 of the 47 listed tags are within 1.5 px: one 20 px tag libapriltag does not decode and
  // two steeply slanted faces whose corners differ by 1.8 and 4.0 px (see docs/markers.md).
  EXPECT_GT(listed_total, 20);
  EXPECT_GE(matched, static_cast<int>(std::ceil(0.9 * listed_total)));
}

TEST(MarkerCsv, RoundTripAndErrors) {
  const auto d = testing::scratch_dir("markers_csv");
  std::vector<MarkerMeasurement> ms{{3, 0.1, 7, {1, 2, 0.01}, 2.5, 30}, {4, 0.133, 8, {-1, 0.5, 0}, 1.5, 10}};
  write_marker_measurements(d / "m.csv", ms);
  const auto r = read_marker_measurements(d / "m.csv");
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[1].id, 8);
  EXPECT_NEAR(r[0].position.y(), 2.0, 1e-9);
  std::ofstream(d / "bad.csv") << "frame,time,id,x,y,z,distance,angle_deg\n1,0.1,3,1,two,0,1,1\n";
  try {
    read_marker_measurements(d / "bad.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.csv:2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'y'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace builtscene
