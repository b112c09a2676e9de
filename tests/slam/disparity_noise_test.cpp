// The robust disparity noise of a bundle-adjustment problem against readings made with a
// known Gaussian noise: the estimate is that noise, and readings that disagree by far (a
// tenth of them, 1.5 px off) move it only as the median of a mixture moves, computed here in
// closed form, while their standard deviation would be several times the noise.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "slam/disparity_noise.hpp"
#include "synthetic_scene.hpp"

namespace builtscene::slam {
namespace {

constexpr double kSigma = 0.08;  // pixels, about the generated Kinect's disparity noise

// Two cameras 0.2 m apart looking down +z at points 1-6 m away (in both images); every point read by both,
// with disparity noise N(0, kSigma); `bad_fraction` of the readings 1.5 px off instead.
BundleAdjustmentProblem readings(int points, double bad_fraction, std::uint32_t seed) {
  BundleAdjustmentProblem pb;
  pb.K = test::kinect();
  pb.K.disparity_sigma = 0.2;
  pb.cameras.push_back({SE3(), true});
  pb.cameras.push_back({SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(-0.2, 0, 0)), false});
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1), depth(1, 6), unit(0, 1);
  std::normal_distribution<double> noise(0, kSigma);
  for (int i = 0; i < points; ++i) {
    const double z = depth(rng);
    const Eigen::Vector3d p(0.3 * z * u(rng), 0.3 * z * u(rng), z);  // in both images
    pb.points.push_back(p);
    for (int c = 0; c < 2; ++c) {
      const Eigen::Vector3d pc = pb.cameras[static_cast<std::size_t>(c)].T_cw * p;
      BundleAdjustmentProblem::Measurement m;
      m.camera = c;
      m.point = i;
      m.o.uv = test::project(pb.K, pc);
      const double d = pb.K.bf / pc.z() + (unit(rng) < bad_fraction ? 1.5 : noise(rng));
      m.o.u_right = m.o.uv.x() - d;
      pb.measurements.push_back(m);
    }
  }
  return pb;
}

TEST(DisparityNoise, IsTheReadingsGaussianNoise) {
  const auto pb = readings(3000, 0.0, 1);
  const auto n = estimate_disparity_noise(pb);
  EXPECT_EQ(n.readings, 6000);
  EXPECT_NEAR(n.sigma, kSigma, 0.05 * kSigma);
}

TEST(DisparityNoise, ReadingsThatDisagreeByFarMoveItOnlyAsTheMedianOfTheMixture) {
  const double bad = 0.1;
  const auto pb = readings(3000, bad, 2);
  const auto n = estimate_disparity_noise(pb);
  // The median of |r| over the mixture is the good readings' quantile 0.5 / (1 - bad) of
  // |N(0, kSigma)|: kSigma * Phi^-1((1 + 0.5 / 0.9) / 2) = kSigma * 0.765 (Phi^-1(0.7778)).
  const double expected = 1.4826 * kSigma * 0.7647;
  EXPECT_NEAR(n.sigma, expected, 0.06 * expected);
  // The plain standard deviation of the same residuals is far off.
  double sum2 = 0;
  for (const auto& m : pb.measurements) {
    const Eigen::Vector3d pc = pb.cameras[static_cast<std::size_t>(m.camera)].T_cw * pb.points[static_cast<std::size_t>(m.point)];
    const double r = pb.K.bf / pc.z() - (m.o.uv.x() - m.o.u_right);
    sum2 += r * r;
  }
  EXPECT_GT(std::sqrt(sum2 / static_cast<double>(pb.measurements.size())), 4 * kSigma);
}

TEST(DisparityNoise, CountsOnlyReadingsOfPointsInFrontAndNeedsEnoughOfThem) {
  auto pb = readings(40, 0.0, 3);
  for (std::size_t m = 0; m < pb.measurements.size(); m += 2) pb.measurements[m].o.u_right = -1;  // monocular
  pb.points.push_back(Eigen::Vector3d(0, 0, -2));  // behind both cameras
  BundleAdjustmentProblem::Measurement behind;
  behind.point = static_cast<int>(pb.points.size()) - 1;
  behind.o.uv = {320, 240};
  behind.o.u_right = 300;
  pb.measurements.push_back(behind);
  const auto n = estimate_disparity_noise(pb, 100);
  EXPECT_EQ(n.readings, 40);
  EXPECT_EQ(n.sigma, 0.0);
  EXPECT_GT(estimate_disparity_noise(pb, 20).sigma, 0.0);
}

}  // namespace
}  // namespace builtscene::slam
