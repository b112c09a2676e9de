// Prior-weighted point-to-plane ICP against depth images rendered from planes with a known
// camera motion (closed form: the depth of a plane along each pixel's ray).
//  * One wall: depth fixes the distance to it and the two tilts; the slide along it and the
//    turn about its normal must stay at the prediction.
//  * A corner of three planes (two walls and the floor) fixes everything: the true motion
//    must come out wherever the prediction was.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "core/so3.hpp"
#include "slam/icp_with_motion_prior.hpp"
#include "plane_depth_render.hpp"
#include "synthetic_scene.hpp"

namespace builtscene::slam {
namespace {

using test::kCx;
using test::kCy;
using test::kFx;
using test::kFy;
using test::Plane;

// Depth image of the planes seen by a camera at T_cw (world -> camera): the nearest hit.
cv::Mat render(const std::vector<Plane>& planes, const SE3& T_cw) { return test::render_planes(planes, T_cw, 6.0); }

// Both are relative motions T_cur_prev: their translations, not camera centres, are compared.
double translation_error(const SE3& a, const SE3& b) { return (a.translation() - b.translation()).norm(); }
using test::rotation_error_deg;

// Camera at the origin looking along +z (world = first camera).
const SE3 kFirst;

TEST(IcpWithMotionPrior, OneWallKeepsThePredictionWhereDepthIsSilent) {
  const std::vector<Plane> wall{{Eigen::Vector3d(0, 0, -1), -2.0}};  // z = 2, facing the camera
  // True motion T_cur_prev: 3 cm towards the wall, 2 cm sideways, a turn of 1 degree about
  // the wall's normal (z) and a tilt of 0.5 degrees about x.
  const SE3 truth(so3_exp(Eigen::Vector3d(0.5, 0, 1.0) * M_PI / 180.0), Eigen::Vector3d(0.02, 0.0, -0.03));
  const cv::Mat prev = render(wall, kFirst), cur = render(wall, truth * kFirst);
  // The prediction knows nothing of the approach or the tilt, but has the slide and the turn
  // wrong by 1 cm / 0.3 degrees: those must stay as predicted, the rest must be measured.
  const SE3 prediction(so3_exp(Eigen::Vector3d(0, 0, 1.3) * M_PI / 180.0), Eigen::Vector3d(0.03, 0.0, 0.0));
  const auto r = icp_with_motion_prior(prev, cur, kFx, kFy, kCx, kCy, prediction);
  ASSERT_TRUE(r.has_value());
  // The distance to the wall after the motion is what depth measures: (T p).z for p on the
  // wall straight ahead. Compare the wall's plane in the current frame instead of raw
  // translations (the tilt couples them): n_c and d_c from the estimate and from the truth.
  auto wall_in_current = [](const SE3& T_cur_prev) {
    const Eigen::Vector3d n = T_cur_prev.rotation_matrix() * Eigen::Vector3d(0, 0, -1);
    const double d = -2.0 + n.dot(T_cur_prev.translation());
    return std::make_pair(n, d);
  };
  const auto [n_est, d_est] = wall_in_current(*r);
  const auto [n_true, d_true] = wall_in_current(truth);
  EXPECT_LT(std::acos(std::min(1.0, n_est.dot(n_true))) * 180.0 / M_PI, 0.05) << "tilt not measured";
  EXPECT_NEAR(d_est, d_true, 0.002) << "distance to the wall not measured";
  // Silent directions: the slide (x, y) and the turn about z stay at the prediction.
  EXPECT_NEAR(r->translation().x(), prediction.translation().x(), 0.003);
  EXPECT_NEAR(so3_log(r->rotation()).z(), so3_log(prediction.rotation()).z(), 0.1 * M_PI / 180.0);
}

TEST(IcpWithMotionPrior, ACornerOfThreePlanesGivesTheTrueMotion) {
  // Corner: a wall ahead (z = 3), a wall to the right (x = 1.2), the floor (y = 1.1; y is down).
  const std::vector<Plane> corner{{Eigen::Vector3d(0, 0, -1), -3.0},
                                  {Eigen::Vector3d(-1, 0, 0), -1.2},
                                  {Eigen::Vector3d(0, -1, 0), -1.1}};
  const SE3 truth(so3_exp(Eigen::Vector3d(0.4, -1.2, 0.6) * M_PI / 180.0), Eigen::Vector3d(0.015, -0.01, 0.025));
  const cv::Mat prev = render(corner, kFirst), cur = render(corner, truth * kFirst);
  for (const SE3& prediction : {SE3(), SE3(so3_exp(Eigen::Vector3d(0, -2.0, 0) * M_PI / 180.0), Eigen::Vector3d(0.04, 0, 0))}) {
    const auto r = icp_with_motion_prior(prev, cur, kFx, kFy, kCx, kCy, prediction);
    ASSERT_TRUE(r.has_value());
    std::printf("corner: prediction off by %.1f mm / %.2f deg -> %.2f mm / %.3f deg\n",
                1000 * translation_error(prediction, truth), rotation_error_deg(prediction, truth),
                1000 * translation_error(*r, truth), rotation_error_deg(*r, truth));
    EXPECT_LT(translation_error(*r, truth), 0.001);
    EXPECT_LT(rotation_error_deg(*r, truth), 0.05);
  }
}

TEST(IcpWithMotionPrior, NoDepthGivesNothing) {
  const cv::Mat empty(480, 640, CV_32F, cv::Scalar(0));
  EXPECT_FALSE(icp_with_motion_prior(empty, empty, kFx, kFy, kCx, kCy, SE3()).has_value());
  EXPECT_FALSE(icp_with_motion_prior(cv::Mat(480, 640, CV_16U), empty, kFx, kFy, kCx, kCy, SE3()).has_value());
}

}  // namespace
}  // namespace builtscene::slam
