// RGB-D frame construction: depth and virtual right coordinate per keypoint, undistortion
// through the camera model, and the grid's area query against a brute-force scan.
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "slam/frame.hpp"
#include "slam/key_frame.hpp"
#include "slam/map_point.hpp"

namespace builtscene::slam {
namespace {

cv::Mat texture() {
  cv::RNG rng(11);
  cv::Mat img(480, 640, CV_8UC1, cv::Scalar(128));
  for (int i = 0; i < 500; ++i)
    cv::circle(img, cv::Point(rng.uniform(0, 640), rng.uniform(0, 480)), rng.uniform(3, 30), cv::Scalar(rng.uniform(0, 256)),
               cv::FILLED);
  return img;
}

RgbdCameraSettings settings(double k1) {
  RgbdCameraSettings s;
  s.camera = {525, 525, 319.5, 239.5, k1, 0, 0, 0, 0, 640, 480};
  s.bf = 40.0;
  return s;
}

// Features of the test texture over a depth image of 3 m on the left half and 7 m on the right.
std::shared_ptr<const FrameFeatures> near_left_far_right(const RgbdCameraSettings& s, OrbExtractor& orb) {
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(3.0f));
  depth(cv::Rect(320, 0, 320, 480)).setTo(7.0f);
  const auto ctx = FrameContext::make(s, orb.pyramid(), DescriptorMetric::orb());
  return make_rgbd_features(texture(), depth, ctx, orb);
}

TEST(Frame, DepthAndVirtualRightCoordinate) {
  OrbExtractor orb;
  const auto ctx = FrameContext::make(settings(0), orb.pyramid(), DescriptorMetric::orb());
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(2.0f));
  depth(cv::Rect(0, 0, 320, 480)).setTo(0.0f);  // left half: no reading
  const auto f = make_rgbd_features(texture(), depth, ctx, orb);
  ASSERT_GT(f->size(), 500u);
  int with = 0;
  for (std::size_t i = 0; i < f->size(); ++i) {
    if (cvRound(f->keys[i].pt.x) < 320) {
      EXPECT_FALSE(f->has_depth(i));
      EXPECT_LT(f->u_right[i], 0);
      continue;
    }
    ++with;
    EXPECT_FLOAT_EQ(f->depth[i], 2.0f);
    EXPECT_NEAR(f->u_right[i], f->keys_un[i].pt.x - 40.0 / 2.0, 1e-4);
    EXPECT_NEAR(f->unproject(i).z(), 2.0, 1e-9);
  }
  EXPECT_GT(with, 100);
  // th_depth = ThDepth * bf / fx = 40 * 40 / 525 m: 2 m is close.
  EXPECT_NEAR(ctx->th_depth, 40.0 * 40.0 / 525.0, 1e-9);
}

// MaxDepth drops readings beyond it at the keypoint (treated as no reading). FarDepth keeps a
// reading beyond it (it places map points) but, as a measurement, gives it no virtual right
// coordinate (measured_u_right < 0), so the optimizers treat the keypoint as monocular. The
// reading's own right coordinate stays (for a view that keeps its far residuals, below).
TEST(Frame, MaxDepthDropsFarReadingsAndFarDepthKeepsThemWithoutDisparity) {
  struct Case {
    double max_depth, far_depth;
    bool far_has_depth, far_measured;
  };
  OrbExtractor orb;
  for (const Case c : {Case{5.0, 0.0, false, false}, Case{0.0, 5.0, true, false}, Case{0.0, 0.0, true, true}}) {
    SCOPED_TRACE("MaxDepth " + std::to_string(c.max_depth) + ", FarDepth " + std::to_string(c.far_depth));
    RgbdCameraSettings s = settings(0);
    s.max_depth = c.max_depth;
    s.far_depth = c.far_depth;
    const auto f = near_left_far_right(s, orb);
    ASSERT_GT(f->size(), 500u);
    int near = 0, far = 0;
    for (std::size_t i = 0; i < f->size(); ++i) {
      const bool right = cvRound(f->keys[i].pt.x) >= 320;
      (right ? far : near) += 1;
      const double z = right ? 7.0 : 3.0;
      const float u_right = static_cast<float>(f->keys_un[i].pt.x - 40.0 / z);
      if (right && !c.far_has_depth) {
        EXPECT_FALSE(f->has_depth(i));
        EXPECT_LT(f->measured_u_right(i, true), 0);
        continue;
      }
      ASSERT_TRUE(f->has_depth(i));
      EXPECT_FLOAT_EQ(f->depth[i], static_cast<float>(z));
      EXPECT_NEAR(f->unproject(i).z(), z, 1e-6);
      EXPECT_NEAR(f->measured_u_right(i, true), u_right, 1e-4);
      if (right && !c.far_measured)
        EXPECT_LT(f->measured_u_right(i), 0);
      else
        EXPECT_NEAR(f->measured_u_right(i), u_right, 1e-4);
    }
    EXPECT_GT(near, 100);
    EXPECT_GT(far, 100);
  }
}

// FarDepth's exception: only a keyframe the depth-odometry bridge made (a pending odometry
// parent, or its tree edge made by odometry) keeps its far readings as disparity measurements;
// with FarDepth off every reading is one anyway.
TEST(Frame, OnlyKeyframesTheBridgeMadeKeepTheirFarReadingsAsMeasurements) {
  OrbExtractor orb;
  RgbdCameraSettings s = settings(0);
  s.far_depth = 5.0;
  const auto f = near_left_far_right(s, orb);
  std::size_t far = f->size();
  for (std::size_t i = 0; i < f->size() && far == f->size(); ++i)
    if (f->is_far(i)) far = i;
  ASSERT_LT(far, f->size());
  Frame frame(0, 0.0, f);
  const auto tracked = std::make_shared<KeyFrame>(1, frame);
  KeyFrame pending(2, frame), linked(3, frame);
  pending.odometry_parent = tracked;
  linked.parent_by_odometry = true;
  EXPECT_FALSE(tracked->keeps_far_readings());
  EXPECT_TRUE(pending.keeps_far_readings());
  EXPECT_TRUE(linked.keeps_far_readings());
  // What the flag does to the far keypoint's measurement: its virtual right coordinate or none.
  EXPECT_LT(f->observation(far, tracked->keeps_far_readings()).u_right, 0);
  EXPECT_NEAR(f->observation(far, linked.keeps_far_readings()).u_right, f->keys_un[far].pt.x - 40.0 / 7.0, 1e-4);
  s.far_depth = 0;  // FarDepth off: nothing is far, nothing to keep
  const auto g = near_left_far_right(s, orb);
  KeyFrame off(4, Frame(1, 0.0, g));
  off.parent_by_odometry = true;
  EXPECT_FALSE(off.keeps_far_readings());
  for (std::size_t i = 0; i < g->size(); ++i) EXPECT_FALSE(g->is_far(i));
}

TEST(Frame, WrongDepthIsIgnoredNotFatal) {
  OrbExtractor orb;
  const auto ctx = FrameContext::make(settings(0), orb.pyramid(), DescriptorMetric::orb());
  for (const cv::Mat& bad : {cv::Mat(), cv::Mat(240, 320, CV_32F, cv::Scalar(1.0f)), cv::Mat(480, 640, CV_16U, cv::Scalar(5000))}) {
    const auto f = make_rgbd_features(texture(), bad, ctx, orb);
    ASSERT_GT(f->size(), 0u);
    for (std::size_t i = 0; i < f->size(); ++i) EXPECT_FALSE(f->has_depth(i));
  }
}

TEST(Frame, UndistortsWithTheCameraModel) {
  OrbExtractor orb;
  const auto s = settings(-0.25);
  const auto ctx = FrameContext::make(s, orb.pyramid(), DescriptorMetric::orb());
  const auto f = make_rgbd_features(texture(), cv::Mat(), ctx, orb);
  ASSERT_GT(f->size(), 500u);
  for (std::size_t i = 0; i < f->size(); ++i) {
    // Independent check: distorting the undistorted point again gives the detected pixel.
    const auto& u = f->keys_un[i].pt;
    const Eigen::Vector2d xn((u.x - s.camera.cx) / s.camera.fx, (u.y - s.camera.cy) / s.camera.fy);
    const Eigen::Vector2d xd = s.camera.distort(xn);
    EXPECT_NEAR(xd.x() * s.camera.fx + s.camera.cx, f->keys[i].pt.x, 0.05);
    EXPECT_NEAR(xd.y() * s.camera.fy + s.camera.cy, f->keys[i].pt.y, 0.05);
  }
  // Barrel distortion (k1 < 0): the undistorted image extends beyond the raw one.
  EXPECT_LT(ctx->min_x, 0.0f);
  EXPECT_GT(ctx->max_x, 640.0f);
}

TEST(Frame, AreaQueryMatchesBruteForce) {
  OrbExtractor orb;
  const auto ctx = FrameContext::make(settings(0), orb.pyramid(), DescriptorMetric::orb());
  const auto f = make_rgbd_features(texture(), cv::Mat(), ctx, orb);
  cv::RNG rng(3);
  for (int q = 0; q < 50; ++q) {
    const float u = static_cast<float>(rng.uniform(-20.0, 660.0)), v = static_cast<float>(rng.uniform(-20.0, 500.0));
    const float r = static_cast<float>(rng.uniform(2.0, 60.0));
    const int min_l = q % 3 == 0 ? 1 : -1, max_l = q % 3 == 0 ? 3 : -1;
    auto got = f->in_area(u, v, r, min_l, max_l);
    std::vector<int> want;
    for (std::size_t i = 0; i < f->size(); ++i) {
      const auto& k = f->keys_un[i];
      if (min_l >= 0 && (k.octave < min_l || k.octave > max_l)) continue;
      if (std::abs(k.pt.x - u) <= r && std::abs(k.pt.y - v) <= r) want.push_back(static_cast<int>(i));
    }
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, want) << "query " << q;
  }
}

}  // namespace
}  // namespace builtscene::slam
