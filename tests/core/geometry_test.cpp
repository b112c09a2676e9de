#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "core/se3.hpp"
#include "core/sim3.hpp"
#include "core/so3.hpp"

namespace builtscene {
namespace {

Eigen::Matrix<double, 6, 1> random_twist(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  Eigen::Matrix<double, 6, 1> xi;
  for (int i = 0; i < 6; ++i) xi(i) = u(rng);
  return xi;
}

// The matrix exponential of the 4x4 twist matrix, by scaling and squaring of the Taylor
// series: an independent route to exp that shares no code with SE3::exp.
Eigen::Matrix4d expm(const Eigen::Matrix4d& A) {
  int squarings = 10;
  Eigen::Matrix4d X = A / std::pow(2.0, squarings);
  Eigen::Matrix4d term = Eigen::Matrix4d::Identity(), sum = Eigen::Matrix4d::Identity();
  for (int k = 1; k < 20; ++k) {
    term = term * X / k;
    sum += term;
  }
  for (int i = 0; i < squarings; ++i) sum = sum * sum;
  return sum;
}

TEST(SO3, ExpMatchesAngleAxisAndLogInverts) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    Eigen::Vector3d axis(u(rng), u(rng), u(rng));
    axis.normalize();
    const double angle = (i % 4 == 0) ? 1e-9 * (i + 1) : std::abs(u(rng)) * (std::numbers::pi - 1e-6);
    const Eigen::Vector3d w = angle * axis;
    const Eigen::Quaterniond q = so3_exp(w);
    const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    EXPECT_LT((q.toRotationMatrix() - R).norm(), 1e-12);
    EXPECT_LT((so3_log(q) - w).norm(), 1e-9 * std::max(1.0, angle));
  }
}

TEST(SO3, LogNearPiKeepsAngle) {
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, 3).normalized();
  const Eigen::Quaterniond q(Eigen::AngleAxisd(std::numbers::pi - 1e-9, axis));
  EXPECT_NEAR(so3_log(q).norm(), std::numbers::pi - 1e-9, 1e-9);
}

TEST(SE3, ExpEqualsMatrixExponentialOfTwist) {
  std::mt19937 rng(2);
  for (int i = 0; i < 50; ++i) {
    const auto xi = random_twist(rng, 1.5);
    Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
    A.topLeftCorner<3, 3>() = skew(xi.tail<3>());
    A.topRightCorner<3, 1>() = xi.head<3>();
    EXPECT_LT((SE3::exp(xi).matrix() - expm(A)).norm(), 1e-10);
    EXPECT_LT((SE3::exp(xi).log() - xi).norm(), 1e-10);
  }
}

TEST(SE3, CompositionInverseAndActionAgreeWithMatrices) {
  std::mt19937 rng(3);
  for (int i = 0; i < 50; ++i) {
    const SE3 a = SE3::exp(random_twist(rng, 2.0)), b = SE3::exp(random_twist(rng, 2.0));
    EXPECT_LT(((a * b).matrix() - a.matrix() * b.matrix()).norm(), 1e-12);
    EXPECT_LT((a.inverse().matrix() - a.matrix().inverse()).norm(), 1e-12);
    const Eigen::Vector3d p(0.3, -1.2, 4.0);
    EXPECT_LT((a * p - (a.matrix() * p.homogeneous()).head<3>()).norm(), 1e-12);
  }
}

TEST(SE3, InterpolationFollowsConstantTwist) {
  // A screw motion: rotation about z by 90 deg while moving 1 m along z.
  const SE3 a;
  const SE3 b(Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ())),
              Eigen::Vector3d(0, 0, 1));
  const SE3 mid = SE3::interpolate(a, b, 0.5);
  EXPECT_NEAR(mid.translation().z(), 0.5, 1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(mid.rotation()).angle(), std::numbers::pi / 4, 1e-12);
  EXPECT_LT((SE3::interpolate(a, b, 1.0).matrix() - b.matrix()).norm(), 1e-12);
  EXPECT_LT((SE3::interpolate(a, b, 0.0).matrix() - a.matrix()).norm(), 1e-12);
}

TEST(Sim3, ExpEqualsMatrixExponentialAndLogInverts) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-0.8, 0.8);
  for (int i = 0; i < 60; ++i) {
    Eigen::Matrix<double, 7, 1> xi;
    for (int k = 0; k < 7; ++k) xi(k) = u(rng);
    if (i % 3 == 0) xi.segment<3>(3) *= 1e-8;  // tiny rotation branch
    if (i % 5 == 0) xi(6) *= 1e-8;             // tiny scale branch
    Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
    A.topLeftCorner<3, 3>() = skew(xi.segment<3>(3)) + xi(6) * Eigen::Matrix3d::Identity();
    A.topRightCorner<3, 1>() = xi.head<3>();
    EXPECT_LT((Sim3::exp(xi).matrix() - expm(A)).norm(), 1e-9) << i;
    EXPECT_LT((Sim3::exp(xi).log() - xi).norm(), 1e-9) << i;
  }
}

TEST(Sim3, CompositionAndInverseAgreeWithMatrices) {
  const Sim3 a(Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 1, 0).normalized())),
               Eigen::Vector3d(1, 2, 3), 2.5);
  const Sim3 b(Eigen::Quaterniond(Eigen::AngleAxisd(-1.1, Eigen::Vector3d::UnitY())), Eigen::Vector3d(-4, 0, 1), 0.3);
  EXPECT_LT(((a * b).matrix() - a.matrix() * b.matrix()).norm(), 1e-12);
  EXPECT_LT((a.inverse().matrix() - a.matrix().inverse()).norm(), 1e-12);
  const Sim3 mid = Sim3::interpolate(Sim3(), Sim3(Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero(), 4.0), 0.5);
  EXPECT_NEAR(mid.scale(), 2.0, 1e-12);
}

}  // namespace
}  // namespace builtscene
