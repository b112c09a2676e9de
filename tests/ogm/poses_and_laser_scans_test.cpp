// PosesAndLaserScans batches: the batching rule, a scan's closed form, and the LCM message as
// an lcm-gen reader sees it.
#include <gtest/gtest.h>

#include <cmath>

#include <lcm/lcm-cpp.hpp>

#include "builtscene/poses_and_laser_scans_t.hpp"
#include "core/errors.hpp"
#include "io/trajectory.hpp"
#include "ogm/lcm_publisher.hpp"
#include "../common/kinect_camera.hpp"
#include "ogm/poses_and_laser_scans.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene {
namespace {

namespace fs = std::filesystem;

using testing::kinect_camera;

// A camera 1 m above the floor (z-up world) looking along +x at a wall 2 m ahead that fills
// the image: every beam within the field of view returns 2 / cos(bearing).
SE3 level_camera_at(double x, double y) {
  Eigen::Matrix3d R;  // columns: camera x (right) = -y_world, camera y (down) = -z, camera z = +x
  R << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return SE3(R, Eigen::Vector3d(x, y, 1.0));
}
cv::Mat wall_depth(double distance) { return cv::Mat(480, 640, CV_32F, cv::Scalar(static_cast<float>(distance))); }

Trajectory keyframes_up_to(int n) {
  Trajectory t;
  for (int i = 0; i < n; ++i) t.push_back({static_cast<double>(i), level_camera_at(0.1 * i, 0)});
  return t;
}

TEST(PosesAndLaserScans, OnePerKeyframeAndAllEveryNthWithCulledOnesDropped) {
  PosesAndLaserScansOptions o;
  o.full_batch_every = 3;
  PosesAndLaserScansEmitter e(kinect_camera(), GroundFrame::z_up(), o);
  std::vector<std::size_t> sizes;
  for (int i = 0; i < 7; ++i) {
    Trajectory kfs = keyframes_up_to(i + 1);
    if (i >= 4) kfs.erase(kfs.begin() + 1);  // keyframe 1 culled by local mapping
    std::reverse(kfs.begin(), kfs.end());    // the SLAM lists keyframes in no particular order
    for (const auto& b : e.add_keyframe(i, level_camera_at(0.1 * i, 0), wall_depth(2.0), kfs)) {
      sizes.push_back(b.pairs.size());
      if (b.full) {
        EXPECT_TRUE(std::is_sorted(b.stamps.begin(), b.stamps.end()));
      }
    }
  }
  // keyframes 0,1,2 | full of 3 | 3,4,5 | full of 5 (1 culled) | 6
  EXPECT_EQ(sizes, (std::vector<std::size_t>{1, 1, 1, 3, 1, 1, 1, 5, 1}));
  EXPECT_EQ(e.keyframes_kept(), 6u);  // the culled keyframe's scan is freed at the full batch

  // A loop closure moves every keyframe: the full batch carries the new poses.
  Trajectory moved = keyframes_up_to(7);
  for (auto& kf : moved) kf.pose = SE3(kf.pose.rotation(), kf.pose.translation() + Eigen::Vector3d(0, 0.5, 0));
  const auto all = e.full_batch(moved);
  ASSERT_EQ(all.pairs.size(), 6u);  // keyframe 1 stays gone
  for (std::size_t i = 0; i < all.pairs.size(); ++i) {
    EXPECT_NEAR(all.pairs[i].pose.y, 0.5, 1e-12);
    EXPECT_NEAR(all.pairs[i].pose.x, 0.1 * all.stamps[i], 1e-12);
    EXPECT_NEAR(all.pairs[i].pose.theta, 0.0, 1e-12);
  }
}

TEST(PosesAndLaserScans, ScanOfAWallIsTheClosedForm) {
  PosesAndLaserScansEmitter e(kinect_camera(), GroundFrame::z_up(), {});
  const auto b = e.add_keyframe(0, level_camera_at(0, 0), wall_depth(2.0), keyframes_up_to(1));
  const LaserScan& s = b.at(0).pairs.at(0).scan;
  // The wall fills the image: beams inside the horizontal field of view (atan(320 / 525) each
  // side) return 2 / cos(bearing); beams outside it (the scanner keeps a margin for tilted
  // cameras) return nothing.
  const double half_fov = std::atan2(320.0, 525.0);
  int inside = 0;
  for (std::size_t i = 0; i < s.ranges.size(); ++i) {
    const double a = s.beam_angle(i);
    if (std::abs(a) < half_fov - s.angle_increment) {
      ++inside;
      ASSERT_TRUE(s.valid(i)) << "beam " << i << " at " << a << " rad";
      EXPECT_NEAR(s.ranges[i], 2.0 / std::cos(a), 0.02) << "beam " << i;
    } else if (std::abs(a) > half_fov + 2 * s.angle_increment) {
      EXPECT_FALSE(s.valid(i)) << "beam " << i << " at " << a << " rad";
    }
  }
  EXPECT_GT(inside, 250);
}

TEST(PosesAndLaserScans, LcmMessageReadsBackThroughLcmGenTypes) {
  const fs::path log = testing::scratch_dir("pals") / "bs_pals.lcmlog";
  fs::remove(log);
  PosesAndLaserScansEmitter e(kinect_camera(), GroundFrame::z_up(), {});
  const auto batch = e.add_keyframe(12.5, level_camera_at(1, 2), wall_depth(2.0), keyframes_up_to(1)).at(0);
  {
    LcmPublisher pub("file://" + log.string() + "?mode=w");
    pub.publish(batch);
  }
  lcm::LogFile in(log.string(), "r");
  ASSERT_TRUE(in.good());
  const lcm::LogEvent* ev = in.readNextEvent();
  ASSERT_NE(ev, nullptr);
  EXPECT_EQ(ev->channel, "POSES_AND_LASER_SCANS");
  builtscene::poses_and_laser_scans_t m;
  ASSERT_EQ(m.decode(ev->data, 0, ev->datalen), ev->datalen);
  EXPECT_FALSE(m.full);
  ASSERT_EQ(m.num_keyframes, 1);
  EXPECT_EQ(m.stamps[0], 12.5);
  EXPECT_EQ(m.poses[0][0], 1.0);
  EXPECT_EQ(m.poses[0][1], 2.0);
  EXPECT_EQ(m.poses[0][2], 1.0);
  EXPECT_NEAR(m.poses2d[0].x, 1.0, 1e-12);
  EXPECT_NEAR(m.poses2d[0].y, 2.0, 1e-12);
  EXPECT_EQ(m.scans[0].ranges, batch.pairs[0].scan.ranges);
  EXPECT_EQ(m.scans[0].angle_increment, batch.pairs[0].scan.angle_increment);
  fs::remove(log);
}

TEST(PosesAndLaserScans, BadLcmUrlIsAnInputError) {
  EXPECT_THROW(LcmPublisher publisher("nosuchprovider://x"), InputError);
}

}  // namespace
}  // namespace builtscene
