// The disparity sigma of a local bundle adjustment (local_ba_disparity.hpp) against windows
// built with known structure and known reading noise: which cameras are held through shared
// points is counted by hand, and the sigma is the clamp of 1.6 times the Gaussian noise the
// readings were made with.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "slam/disparity_noise.hpp"
#include "slam/local_ba_disparity.hpp"
#include "synthetic_scene.hpp"

namespace builtscene::slam {
namespace {

// Cameras along x, 0.2 m apart, looking down +z; camera 0 fixed.
BundleAdjustmentProblem cameras(int n) {
  BundleAdjustmentProblem pb;
  pb.K = test::kinect();
  pb.K.disparity_sigma = 0.2;
  for (int c = 0; c < n; ++c)
    pb.cameras.push_back({SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(-0.2 * c, 0, 0)), c == 0});
  return pb;
}

// `count` new points 2-5 m ahead, each seen by every camera in `seen_by`; read (with disparity
// noise N(0, sigma)) by the cameras in `read_by`, monocular in the others.
void add_points(BundleAdjustmentProblem& pb, int count, const std::vector<int>& seen_by, const std::vector<int>& read_by,
                double sigma, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1), depth(2, 5);
  std::normal_distribution<double> noise(0, sigma);
  for (int i = 0; i < count; ++i) {
    const double z = depth(rng);
    pb.points.push_back(Eigen::Vector3d(0.2 * z * u(rng), 0.2 * z * u(rng), z));
    const int p = static_cast<int>(pb.points.size()) - 1;
    for (int c : seen_by) {
      const Eigen::Vector3d pc = pb.cameras[static_cast<std::size_t>(c)].T_cw * pb.points.back();
      BundleAdjustmentProblem::Measurement m;
      m.camera = c;
      m.point = p;
      m.o.uv = test::project(pb.K, pc);
      m.o.u_right = -1;
      if (std::find(read_by.begin(), read_by.end(), c) != read_by.end())
        m.o.u_right = m.o.uv.x() - (pb.K.bf / pc.z() + noise(rng));
      pb.measurements.push_back(m);
    }
  }
}

// The rule as `slam --adaptive-ba-disparity` sets it (off by default).
LocalBADisparityOptions on() {
  LocalBADisparityOptions o;
  o.adaptive = true;
  return o;
}

TEST(LocalBADisparity, FreeCamerasAreHeldThroughPairsSharingEnoughPoints) {
  std::mt19937 rng(1);
  auto pb = cameras(4);  // 0 fixed; 1, 2, 3 free
  add_points(pb, 40, {0, 1}, {}, 0, rng);
  add_points(pb, 40, {1, 2}, {}, 0, rng);
  add_points(pb, 29, {2, 3}, {}, 0, rng);
  // Camera 3 shares 29 points with camera 2 and none with another: not held at 30, held at 29.
  EXPECT_FALSE(free_cameras_held_by_fixed(pb, 30));
  EXPECT_TRUE(free_cameras_held_by_fixed(pb, 29));
  // Points seen by three cameras count for every pair: one more such point joins camera 3.
  add_points(pb, 1, {1, 2, 3}, {}, 0, rng);
  EXPECT_TRUE(free_cameras_held_by_fixed(pb, 30));
  // Without a fixed camera nothing is held.
  pb.cameras[0].fixed = false;
  EXPECT_FALSE(free_cameras_held_by_fixed(pb, 30));
}

TEST(LocalBADisparity, SigmaIsTheClampOfTheMeasuredNoiseTimesTheFactor) {
  const LocalBADisparityOptions o = on();  // factor 1.6, floor 0.1 px, DisparitySigma 0.2 px above
  for (const auto& [noise, expected] : std::vector<std::pair<double, double>>{{0.08, 1.6 * 0.08}, {0.03, 0.1}, {0.3, 0.2}}) {
    std::mt19937 rng(2);
    auto pb = cameras(2);
    add_points(pb, 1500, {0, 1}, {0, 1}, noise, rng);
    const auto c = choose_local_ba_disparity_sigma(pb, o);
    EXPECT_TRUE(c.held);
    EXPECT_NEAR(c.measured, noise, 0.06 * noise) << noise;
    EXPECT_NEAR(c.sigma, expected, 0.06 * expected) << noise;
  }
}

TEST(LocalBADisparity, ReadingsOfPointsReadOnceDoNotCount) {
  // Every point read by camera 1 only (camera 0 sees it without depth): their residuals say
  // nothing of the sensor, so nothing is measured and DisparitySigma stays.
  std::mt19937 rng(3);
  auto pb = cameras(2);
  add_points(pb, 500, {0, 1}, {1}, 0.08, rng);
  EXPECT_GT(estimate_disparity_noise(pb).readings, 100);
  const auto c = choose_local_ba_disparity_sigma(pb, on());
  EXPECT_TRUE(c.held);
  EXPECT_EQ(c.measured, 0.0);
  EXPECT_EQ(c.sigma, 0.2);
}

TEST(LocalBADisparity, AWindowNotHeldOrTheRuleOffOrOrbSlamsFormKeepsTheSigma) {
  std::mt19937 rng(4);
  auto pb = cameras(3);
  add_points(pb, 800, {0, 1}, {0, 1}, 0.05, rng);
  add_points(pb, 10, {1, 2}, {1, 2}, 0.05, rng);  // camera 2: 10 shared points
  add_points(pb, 300, {2}, {2}, 0.05, rng);
  auto c = choose_local_ba_disparity_sigma(pb, on());
  EXPECT_FALSE(c.held);
  EXPECT_EQ(c.sigma, 0.2);
  LocalBADisparityOptions loose = on();
  loose.min_shared_points = 10;
  c = choose_local_ba_disparity_sigma(pb, loose);
  EXPECT_TRUE(c.held);
  EXPECT_NEAR(c.sigma, 0.1, 1e-12);  // 1.6 x 0.05 = 0.08, floored at 0.1
  LocalBADisparityOptions off = loose;
  off.adaptive = false;
  EXPECT_EQ(choose_local_ba_disparity_sigma(pb, off).sigma, 0.2);
  EXPECT_EQ(choose_local_ba_disparity_sigma(pb, {}).sigma, 0.2);  // the default is off
  pb.K.disparity_sigma = 0;  // ORB-SLAM's u_right residual: no disparity sigma to choose
  EXPECT_EQ(choose_local_ba_disparity_sigma(pb, loose).sigma, 0.0);
}

}  // namespace
}  // namespace builtscene::slam
