// Acceptance runs of issue 4 on generated worlds, shortened so CI stays fast: 300 frames of
// `lab-room` carried by hand (two seeds, each with at least one fast turn) and 300 frames of
// the robot driving `corridor-loop`, all with Kinect noise, against the worlds' exact ground
// truth. Local mapping runs inline (deterministic); the full-length numbers (900 frames, the
// whole loop) are in docs/slam.md with their commands.
#include <unistd.h>

#include <filesystem>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "eval/trajectory_error.hpp"
#include "io/tum_dataset.hpp"
#include "slam/system.hpp"
#include "generated_world.hpp"

namespace builtscene::slam {
namespace {

struct WorldRun {
  std::size_t frames = 0;
  int tracked = 0;
  std::size_t keyframes = 0;
  Trajectory trajectory;
  AteResult ate;
  double sim3_scale = 0;  // est -> truth; 1 when the trajectory has the true size
  double end_drift_m = 0;  // last tracked pose against the truth, after the se3 alignment
};

WorldRun track(const std::filesystem::path& dir) {
  const auto data = TumDataset::open(dir);
  SystemOptions so;
  so.mapping_thread = false;
  System slam(data.settings(), so);
  WorldRun r;
  r.frames = data.size();
  for (std::size_t i = 0; i < data.size(); ++i) {
    const auto out = slam.track_rgbd(data.load_rgb(i), data.load_depth(i), data.entry(i).timestamp);
    r.tracked += out.state == TrackingState::kOk;
  }
  slam.shutdown();
  r.keyframes = slam.keyframe_count();
  r.trajectory = slam.trajectory();
  r.ate = absolute_trajectory_error(data.groundtruth(), r.trajectory, Alignment::kSE3);
  if (!r.ate.errors.empty()) r.end_drift_m = r.ate.errors.back();
  r.sim3_scale = absolute_trajectory_error(data.groundtruth(), r.trajectory, Alignment::kSim3).est_to_gt.scale();
  return r;
}

WorldRun generate_and_track(const std::string& scene, synth::MotionKind motion, std::uint64_t seed, int frames) {
  const GeneratedWorld world(scene, motion, seed, frames);
  const auto r = track(world.dir);
  std::printf("%s seed %llu: tracked %d/%zu, keyframes %zu, ATE RMSE %.2f cm (median %.2f, max %.2f), last pose %.2f cm, "
              "sim3 scale %.4f\n",
              scene.c_str(), static_cast<unsigned long long>(seed), r.tracked, r.frames, r.keyframes,
              100 * r.ate.stats.rmse, 100 * r.ate.stats.median, 100 * r.ate.stats.max, 100 * r.end_drift_m, r.sim3_scale);
  return r;
}

class LabRoomHandheld : public ::testing::TestWithParam<std::uint64_t> {};

// Issue 4: every frame tracked, ATE RMSE <= 2 cm with se3 alignment.
TEST_P(LabRoomHandheld, TracksEveryFrameWithinTwoCentimetres) {
  const auto r = generate_and_track("lab-room", synth::MotionKind::Handheld, GetParam(), 300);
  ASSERT_EQ(r.frames, 300u);
  EXPECT_EQ(r.tracked, 300);
  EXPECT_EQ(r.ate.stats.count, static_cast<std::size_t>(r.tracked));
  EXPECT_LE(r.ate.stats.rmse, 0.02);
}

INSTANTIATE_TEST_SUITE_P(TwoSeeds, LabRoomHandheld, ::testing::Values(1u, 2u));

// Issue 4: at least 99 % of the robot's frames tracked; the error at the end is reported
// (printed), not bounded: the issue asks for no bound, and the full loop does not yet meet
// even the tracking one (docs/slam.md, "Generated worlds").
TEST(CorridorLoopRobot, TracksNinetyNinePercentOfFrames) {
  const auto r = generate_and_track("corridor-loop", synth::MotionKind::Robot, 1, 300);
  ASSERT_EQ(r.frames, 300u);
  EXPECT_GE(r.tracked, 297);
  EXPECT_EQ(r.ate.stats.count, static_cast<std::size_t>(r.tracked));
  // The trajectory has the true size: noise corners on the plain walls and under-weighted
  // depth used to shrink it by 9-16 % (sim3 scale 1.09-1.16; docs/slam.md, "Image noise").
  EXPECT_NEAR(r.sim3_scale, 1.0, 0.02);
}

// Same input, same output (DESIGN: determinism). With local mapping inline nothing depends
// on thread timing, so two runs over one sequence must give the same poses to the bit. They
// did not while keyframes and points sat in containers ordered by heap address (3 different
// trajectories in 6 runs of 300 lab-room frames): the second run here allocates its map
// after the first one's was freed, so its addresses differ.
TEST(SlamDeterminism, TwoRunsOverOneSequenceGiveIdenticalPoses) {
  const GeneratedWorld world("lab-room", synth::MotionKind::Handheld, 3, 200);
  const auto a = track(world.dir);
  std::vector<std::unique_ptr<int[]>> shift;  // moves the second run's allocations elsewhere
  for (int i = 1; i < 64; ++i) shift.push_back(std::make_unique<int[]>(static_cast<std::size_t>(i * 37)));
  const auto b = track(world.dir);
  std::printf("run 1: %d tracked, %zu keyframes; run 2: %d tracked, %zu keyframes\n", a.tracked, a.keyframes,
              b.tracked, b.keyframes);
  ASSERT_GT(a.keyframes, 5u);  // a run long enough to exercise covisibility, culling and BA
  EXPECT_EQ(a.keyframes, b.keyframes);
  ASSERT_EQ(a.trajectory.size(), b.trajectory.size());
  int differing = 0;
  for (std::size_t i = 0; i < a.trajectory.size(); ++i) {
    const auto& pa = a.trajectory[i];
    const auto& pb = b.trajectory[i];
    const bool same = pa.timestamp == pb.timestamp && pa.pose.translation() == pb.pose.translation() &&
                      pa.pose.rotation().coeffs() == pb.pose.rotation().coeffs();
    differing += !same;
  }
  EXPECT_EQ(differing, 0) << "poses differ between two runs over the same input";
}

}  // namespace
}  // namespace builtscene::slam
