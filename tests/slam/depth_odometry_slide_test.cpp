// The depth odometry along a corridor, on depth images ray-cast from planes with the Kinect
// noise model of the generated worlds (disparity steps, axial noise), camera moving straight
// down the corridor at 2.34 cm per frame (the generated robot's speed), the prediction at 1.8.
//  * A plain corridor (floor, ceiling, two walls): nothing in the depth measures the motion
//    along the corridor, so the only honest answer there is the prediction. The disparity steps
//    sit at fixed distances from the camera and pull plain ICP towards no motion; the
//    odometry must neither follow them nor call the slide measured.
//  * The same corridor with an end wall 2.5 m ahead: the depth measures the motion, the true
//    2.34 cm must come out whatever the prediction, and the slide counts as measured (the
//    tracker takes such frames' speeds for its prediction).
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "slam/depth_odometry.hpp"
#include "slam/icp_with_motion_prior.hpp"
#include "synth/sensor_noise.hpp"
#include "plane_depth_render.hpp"

namespace builtscene::slam {
namespace depth_odometry_slide_test {

constexpr double kTrueStep = 0.0234, kPredictedStep = 0.018;
constexpr int kFrames = 12;

using test::kCx;
using test::kCy;
using test::kFx;
using test::kFy;
using test::Plane;

// Camera looking along +z, y down, at z = position; Kinect-like depth of the nearest plane.
cv::Mat render(const std::vector<Plane>& planes, double position, int frame) {
  cv::Mat incidence;
  const cv::Mat depth =
      test::render_planes(planes, SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, -position)), 0, &incidence);
  synth::FrameRng rng(7, static_cast<std::uint64_t>(frame), 1);
  return synth::apply_kinect_noise(depth, incidence, synth::KinectNoiseModel{}, rng);
}

struct CorridorRun {
  double odometry_step = 0, plain_icp_step = 0;  // mean motion along the corridor per frame
  int measured = 0;
};

CorridorRun run(const std::vector<Plane>& planes) {
  DepthOdometry odometry(kFx, kFy, kCx, kCy);
  const cv::Mat gray(480, 640, CV_8U, cv::Scalar(128));
  // T_cur_prev of a camera moving +z by s: points move -s in z.
  const SE3 prediction(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, -kPredictedStep));
  CorridorRun r;
  cv::Mat prev = render(planes, 0.0, 0);
  for (int i = 1; i <= kFrames; ++i) {
    const cv::Mat cur = render(planes, i * kTrueStep, i);
    const auto T = odometry.align(gray, prev, gray, cur, prediction, /*keep_guess_along_slide=*/true);
    EXPECT_TRUE(T.has_value()) << "frame " << i;
    if (T) r.odometry_step += -T->translation().z() / kFrames;
    r.measured += odometry.last_slide_measured();
    const auto plain = icp_with_motion_prior(prev, cur, kFx, kFy, kCx, kCy, prediction);
    if (plain) r.plain_icp_step += -plain->translation().z() / kFrames;
    prev = cur;
  }
  std::printf("truth %.2f cm, prediction %.2f cm: odometry %.2f cm (slide measured on %d of %d), plain ICP %.2f cm\n",
              100 * kTrueStep, 100 * kPredictedStep, 100 * r.odometry_step, r.measured, kFrames, 100 * r.plain_icp_step);
  return r;
}

const Plane kFloor{Eigen::Vector3d(0, 1, 0), 1.1}, kCeiling{Eigen::Vector3d(0, -1, 0), 1.4},
    kLeft{Eigen::Vector3d(-1, 0, 0), 1.2}, kRight{Eigen::Vector3d(1, 0, 0), 1.2};

TEST(DepthOdometrySlide, APlainCorridorKeepsThePredictedSpeedAndSaysSo) {
  const CorridorRun r = run({kFloor, kCeiling, kLeft, kRight});
  EXPECT_NEAR(r.odometry_step, kPredictedStep, 0.0002);  // plain ICP: 0.04 cm short
  EXPECT_LE(r.measured, kFrames / 4);
}

TEST(DepthOdometrySlide, AnEndWallInRangeMeasuresTheTrueSpeed) {
  const CorridorRun r = run({kFloor, kCeiling, kLeft, kRight, {Eigen::Vector3d(0, 0, 1), 2.5}});
  EXPECT_NEAR(r.odometry_step, kTrueStep, 0.001);
  EXPECT_GE(r.measured, kFrames * 3 / 4);
}

}  // namespace depth_odometry_slide_test
}  // namespace builtscene::slam
