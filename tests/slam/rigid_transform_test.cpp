// fit_rigid_transform against transforms chosen by the test: the fit must return them.
#include <gtest/gtest.h>

#include <random>

#include "slam/rigid_transform.hpp"
#include "slam/rigid_transform_ransac.hpp"

using builtscene::slam::fit_rigid_transform;

TEST(RigidTransform, RecoversKnownTransformFromExactPairs) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
  truth.linear() = Eigen::AngleAxisd(2.5, Eigen::Vector3d(0.3, -1.0, 0.4).normalized()).toRotationMatrix();
  truth.translation() = Eigen::Vector3d(1.5, -0.7, 4.0);
  std::vector<Eigen::Vector3d> src, dst;
  for (int i = 0; i < 20; ++i) {
    src.emplace_back(u(rng), u(rng), u(rng));
    dst.push_back(truth * src.back());
  }
  const auto fit = fit_rigid_transform(src, dst);
  ASSERT_TRUE(fit.has_value());
  EXPECT_LT((fit->linear() - truth.linear()).norm(), 1e-9);
  EXPECT_LT((fit->translation() - truth.translation()).norm(), 1e-9);
  EXPECT_NEAR(fit->linear().determinant(), 1.0, 1e-9);
}

TEST(RigidTransform, RejectsTooFewOrCollinearPoints) {
  std::vector<Eigen::Vector3d> two{{0, 0, 0}, {1, 0, 0}};
  EXPECT_FALSE(fit_rigid_transform(two, two).has_value());
  std::vector<Eigen::Vector3d> line{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  EXPECT_FALSE(fit_rigid_transform(line, line).has_value());
}

TEST(RigidTransformRansac, RecoversTransformAndOutliersFromContaminatedPairs) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  std::normal_distribution<double> noise(0.0, 0.005);
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
  truth.linear() = Eigen::AngleAxisd(-1.1, Eigen::Vector3d(1.0, 0.2, 0.5).normalized()).toRotationMatrix();
  truth.translation() = Eigen::Vector3d(-2.0, 0.3, 1.0);
  std::vector<Eigen::Vector3d> src, dst;
  std::vector<bool> is_outlier;
  for (int i = 0; i < 100; ++i) {
    src.emplace_back(u(rng), u(rng), u(rng));
    const bool outlier = i % 5 < 2;  // 40 % wrong matches
    is_outlier.push_back(outlier);
    dst.push_back(outlier ? Eigen::Vector3d(u(rng), u(rng), u(rng))
                          : Eigen::Vector3d(truth * src.back() + Eigen::Vector3d(noise(rng), noise(rng), noise(rng))));
  }
  const auto fit = builtscene::slam::ransac_rigid_transform(src, dst, 0.05, 40, 200, 3);
  ASSERT_TRUE(fit.has_value());
  EXPECT_LT((fit->transform.linear() - truth.linear()).norm(), 5e-3);
  EXPECT_LT((fit->transform.translation() - truth.translation()).norm(), 5e-3);
  for (std::size_t i = 0; i < src.size(); ++i) EXPECT_EQ(fit->inliers[i], !is_outlier[i]) << i;
}

TEST(RigidTransformRansac, RejectsUnrelatedPointSets) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  std::vector<Eigen::Vector3d> src, dst;
  for (int i = 0; i < 60; ++i) {
    src.emplace_back(u(rng), u(rng), u(rng));
    dst.emplace_back(u(rng), u(rng), u(rng));
  }
  EXPECT_FALSE(builtscene::slam::ransac_rigid_transform(src, dst, 0.05, 20, 200, 3).has_value());
}
