// Acceptance runs of issue 4 on generated worlds, shortened so CI stays fast: 300 frames of
// `lab-room` carried by hand (two seeds, each with at least one fast turn) and 300 frames of
// the robot driving `corridor-loop`, all with Kinect noise, against the worlds' exact ground
// truth. Local mapping runs inline (deterministic); the full-length numbers (900 frames, the
// whole loop) are in docs/slam.md with their commands.
#include <unistd.h>

#include <filesystem>

#include <gtest/gtest.h>

#include "eval/trajectory_error.hpp"
#include "io/tum_dataset.hpp"
#include "slam/system.hpp"
#include "synth/rgbd_sequence_writer.hpp"

namespace builtscene::slam {
namespace {

struct WorldRun {
  std::size_t frames = 0;
  int tracked = 0;
  AteResult ate;
  double end_drift_m = 0;  // last tracked pose against the truth, after the se3 alignment
};

WorldRun generate_and_track(const std::string& scene, synth::MotionKind motion, std::uint64_t seed, int frames) {
  synth::RgbdSequenceOptions o;
  o.scene = scene;
  o.motion = motion;
  o.seed = seed;
  o.frames = frames;
  o.kinect_noise = true;
  o.out = std::filesystem::temp_directory_path() /
          ("builtscene_slam_world_" + scene + "_" + std::to_string(seed) + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(o.out);
  // Removed on every exit, also when evaluation throws (a folder of 300 frames is 250 MB).
  struct RemoveOnExit {
    std::filesystem::path dir;
    ~RemoveOnExit() { std::filesystem::remove_all(dir); }
  } cleanup{o.out};
  synth::generate_rgbd_sequence(o);

  const auto data = TumDataset::open(o.out);
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
  const auto traj = slam.trajectory();
  r.ate = absolute_trajectory_error(data.groundtruth(), traj, Alignment::kSE3);
  if (!r.ate.errors.empty()) r.end_drift_m = r.ate.errors.back();
  std::printf("%s seed %llu: tracked %d/%zu, keyframes %zu, ATE RMSE %.2f cm (median %.2f, max %.2f), last pose %.2f cm\n",
              scene.c_str(), static_cast<unsigned long long>(seed), r.tracked, r.frames, slam.keyframe_count(),
              100 * r.ate.stats.rmse, 100 * r.ate.stats.median, 100 * r.ate.stats.max, 100 * r.end_drift_m);
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
}

}  // namespace
}  // namespace builtscene::slam
