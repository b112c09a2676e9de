// The SLAM with SAFT descriptors (issue 8, items 1, 5, 6) on a generated room carried by hand
// (noise-free, see below), against the world's exact ground truth: it tracks with the pre-trained net and with online
// learning, the learner's weights reach the prediction net, and every training pair the
// tracking thread prepares is what it claims to be: the two patches of a positive pair show
// one 3D point of the world, those of a negative pair two different ones (checked with the
// ground-truth poses and depth images, not with the SLAM's own associations).
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <vector>

#include <gtest/gtest.h>

#include "eval/trajectory_error.hpp"
#include "generated_world.hpp"
#include "io/tum_dataset.hpp"
#include "slam/system.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene::slam {
namespace {

struct SaftRun {
  int tracked = 0;
  double ate_rmse = 0;
  SaftLearning::Stats learning;
  std::vector<SaftLabelledPairs> batches;  // every 10th prepared batch
  int inlier_frames = 0;                   // frames with both Figure 3.13 ratios in [0, 1]
  Trajectory trajectory;
  Sim3 est_to_gt;                          // the se3 alignment of the ATE
};

// `map_out`: the map is saved there at the end.
SaftRun run(const TumDataset& data, SaftLearningMode mode, bool synchronous = false, int max_passes = 20,
            const std::filesystem::path& map_out = {}, const std::function<void(SaftLearningOptions&)>& tune = {}) {
  SystemOptions so;
  so.mapping_thread = false;
  so.descriptor = DescriptorChoice::kSaft;
  so.saft_learning.mode = mode;
  so.saft_learning.synchronous = synchronous;
  so.saft_learning.max_passes = max_passes;
  SaftRun r;
  int seen = 0;
  so.saft_learning.on_batch = [&](const SaftLabelledPairs& b) {
    if (seen++ % 10 == 0) r.batches.push_back(b);
  };
  if (tune) tune(so.saft_learning);
  System slam(data.settings(), so);
  for (std::size_t i = 0; i < data.size(); ++i) {
    const auto out = slam.track_rgbd(data.load_rgb(i), data.load_depth(i), data.entry(i).timestamp);
    r.tracked += out.state == TrackingState::kOk;
    if (out.initial_matches > 0 && out.local_map_matches > 0 && out.initial_inliers <= out.initial_matches &&
        out.local_map_inliers <= out.local_map_matches)
      ++r.inlier_frames;
  }
  slam.shutdown();
  r.learning = slam.saft_learning()->stats();
  r.trajectory = slam.trajectory();
  const auto ate = absolute_trajectory_error(data.groundtruth(), r.trajectory, Alignment::kSE3);
  r.ate_rmse = ate.stats.rmse;
  r.est_to_gt = ate.est_to_gt;
  if (!map_out.empty()) slam.save_map(map_out);
  return r;
}

// The world point a patch shows: its keypoint's pixel and depth through the true pose.
struct Truth {
  const TumDataset& data;
  Trajectory gt;
  std::map<long, cv::Mat> depth;
  explicit Truth(const TumDataset& d) : data(d), gt(d.groundtruth()) {}
  std::optional<Eigen::Vector3d> point(const SaftLabelledPairs::Source& s) {
    if (!depth.count(s.frame)) depth[s.frame] = data.load_depth(static_cast<std::size_t>(s.frame));
    const cv::Mat& dm = depth[s.frame];
    const int x = cvRound(s.pixel.x), y = cvRound(s.pixel.y);
    if (x < 0 || y < 0 || x >= dm.cols || y >= dm.rows) return std::nullopt;
    const float z = dm.at<float>(y, x);
    if (!(z > 0)) return std::nullopt;
    const double t = data.entry(static_cast<std::size_t>(s.frame)).timestamp;
    const StampedPose* best = nullptr;
    for (const auto& p : gt)
      if (!best || std::abs(p.timestamp - t) < std::abs(best->timestamp - t)) best = &p;
    if (!best || std::abs(best->timestamp - t) > 1e-3) return std::nullopt;
    return best->pose * data.settings().camera.unproject({s.pixel.x, s.pixel.y}, z);
  }
};

TEST(SaftSlam, TracksAGeneratedRoomOfflineAndWhileLearningWithTruePairs) {
  // Without sensor noise: the pair check unprojects single depth pixels, and the Kinect
  // model's depth noise (1-3 cm at 2-4 m, twice over) would blur a 5 cm test. (With noise
  // the median positive-pair distance was 3.0 cm, without it 0.9 cm.)
  const GeneratedWorld world("lab-room", synth::MotionKind::Handheld, 4, 150, /*kinect_noise=*/false);
  const auto data = TumDataset::open(world.dir);
  const int n = static_cast<int>(data.size());

  const SaftRun offline = run(data, SaftLearningMode::kOffline);
  std::printf("offline SAFT: tracked %d/%d, ATE %.2f cm\n", offline.tracked, n, 100 * offline.ate_rmse);
  EXPECT_GE(offline.tracked, n * 95 / 100);
  EXPECT_LT(offline.ate_rmse, 0.03);
  EXPECT_EQ(offline.learning.batches_prepared, 0);
  EXPECT_GE(offline.inlier_frames, n * 9 / 10);

  const SaftRun online = run(data, SaftLearningMode::kContinuous);
  std::printf("continuous SAFT: tracked %d/%d, ATE %.2f cm, %ld batches, %ld trained, %ld weight updates, accuracy %.3f -> %.3f\n",
              online.tracked, n, 100 * online.ate_rmse, online.learning.batches_prepared, online.learning.batches_trained,
              online.learning.weight_updates, online.learning.first_accuracy, online.learning.last_accuracy);
  EXPECT_GE(online.tracked, n * 95 / 100);
  EXPECT_LT(online.ate_rmse, 0.03);
  EXPECT_GT(online.learning.batches_prepared, n / 2);
  EXPECT_GE(online.learning.batches_trained, 1);
  EXPECT_GE(online.learning.weight_updates, 1);

  // Every sampled pair against the ground truth.
  Truth truth(data);
  int pos = 0, pos_same = 0, neg = 0, neg_apart = 0;
  ASSERT_FALSE(online.batches.empty());
  for (const auto& b : online.batches) {
    ASSERT_EQ(b.first_source.size(), b.label.size());
    int p = 0;
    for (int l : b.label) p += l > 0;
    EXPECT_EQ(2 * p, b.size());  // balanced
    for (std::size_t i = 0; i < b.label.size(); ++i) {
      if (b.label[i] > 0) {
        EXPECT_NE(b.first_source[i].frame, b.second_source[i].frame);  // two views of the point
      }
      const auto a = truth.point(b.first_source[i]), c = truth.point(b.second_source[i]);
      if (!a || !c) continue;
      const double d = (*a - *c).norm();
      if (b.label[i] > 0) {
        ++pos;
        pos_same += d < 0.05;
      } else {
        ++neg;
        neg_apart += d > 0.05;
      }
    }
  }
  std::printf("pairs checked: %d positive (%d within 5 cm), %d negative (%d farther than 5 cm)\n", pos, pos_same, neg, neg_apart);
  ASSERT_GT(pos, 200);
  ASSERT_GT(neg, 200);
  EXPECT_GE(pos_same, pos * 95 / 100);
  EXPECT_GE(neg_apart, neg * 95 / 100);
}

TEST(SaftSlam, DiscreteLearningReleasesWeightsAfterSeveralPassesOverABatch) {
  // Discrete: several passes over one batch, then the weights go to the prediction net (at the
  // target accuracy or after max_passes). With a target no anchored run reached, the first
  // version never released any weights: discrete SAFT was offline SAFT under another name.
  // Synchronous learning, so every batch is trained whatever the machine's load, and a
  // second run gives the same poses (what `slam --sync-mapping` promises).
  constexpr int kMaxPasses = 4;
  const GeneratedWorld world("lab-room", synth::MotionKind::Handheld, 5, 20, /*kinect_noise=*/false);
  const auto data = TumDataset::open(world.dir);
  const int n = static_cast<int>(data.size());
  const SaftRun discrete = run(data, SaftLearningMode::kDiscrete, /*synchronous=*/true, kMaxPasses);
  const auto& s = discrete.learning;
  std::printf("discrete SAFT: tracked %d/%d, ATE %.2f cm, %ld trained, %ld passes, %ld at target, %ld weight updates\n",
              discrete.tracked, n, 100 * discrete.ate_rmse, s.batches_trained, s.passes, s.target_reached, s.weight_updates);
  EXPECT_GE(discrete.tracked, n * 95 / 100);
  EXPECT_LT(discrete.ate_rmse, 0.03);
  ASSERT_GE(s.batches_trained, n / 2);
  EXPECT_EQ(s.batches_trained, s.batches_prepared);  // synchronous: none dropped
  // Every batch released weights, and the prediction net took each before the next frame
  // (a batch of the last frame releases its weights after it).
  EXPECT_GE(s.weight_updates, s.batches_trained - 1);
  EXPECT_LE(s.weight_updates, s.batches_trained);
  // A batch not released by the target took all kMaxPasses passes.
  EXPECT_LE(s.passes, kMaxPasses * s.batches_trained);
  EXPECT_GE(s.passes, s.target_reached + kMaxPasses * (s.batches_trained - s.target_reached));
  EXPECT_GT(s.passes, s.batches_trained);  // more than one pass per batch

  const SaftRun again = run(data, SaftLearningMode::kDiscrete, /*synchronous=*/true, kMaxPasses);
  ASSERT_EQ(again.trajectory.size(), discrete.trajectory.size());
  for (std::size_t i = 0; i < again.trajectory.size(); ++i)
    EXPECT_TRUE(again.trajectory[i].pose.matrix() == discrete.trajectory[i].pose.matrix()) << "pose " << i;
  EXPECT_EQ(again.learning.passes, s.passes);
}

// The hand-over check (continuous mode) inside the SLAM: every batch is trained once, and its
// weights are either installed before the next frame or refused (whether the held-out pairs
// gained is SaftOnlineTrainer.CheckedPass*'s check); tracking is unharmed either way.
TEST(SaftSlam, WithTheHandOverCheckEveryBatchIsInstalledOrRefused) {
  const GeneratedWorld world("lab-room", synth::MotionKind::Handheld, 6, 30, /*kinect_noise=*/false);
  const auto data = TumDataset::open(world.dir);
  const int n = static_cast<int>(data.size());
  const SaftRun checked = run(data, SaftLearningMode::kContinuous, /*synchronous=*/true, 20, {},
                              [](SaftLearningOptions& o) { o.handover_check = true; });
  const auto& c = checked.learning;
  std::printf("checked continuous SAFT: tracked %d/%d, ATE %.2f cm, %ld trained, %ld installed, %ld refused\n",
              checked.tracked, n, 100 * checked.ate_rmse, c.batches_trained, c.weight_updates, c.handovers_refused);
  ASSERT_GE(c.batches_trained, n / 2);
  EXPECT_EQ(c.batches_trained, c.batches_prepared);  // synchronous: none dropped
  EXPECT_EQ(c.passes, c.batches_trained);            // one pass per batch, as continuous
  // The last frame's batch, when kept, is installed only after the run.
  EXPECT_GE(c.weight_updates + c.handovers_refused, c.batches_trained - 1);
  EXPECT_LE(c.weight_updates + c.handovers_refused, c.batches_trained);
  EXPECT_GE(checked.tracked, n * 95 / 100);
  EXPECT_LT(checked.ate_rmse, 0.03);
}

// A map built while the net learned holds descriptors of many nets. They must stay in the
// pre-trained net's space (the anchor's job; at this length the test also passes without it,
// docs/saft.md), so that another run with the pre-trained net relocalizes in that map (bag of words with the shipped SAFT vocabulary, then descriptor
// matching) and localizes there: the issue 5 localization acceptance, with SAFT and a map
// made by online learning. Robot sequences of the room with Kinect noise: A (seed 1) builds
// the map, C (seed 3) drives the same loop from the same start (as in saved_map_test).
TEST(SaftSlam, AMapBuiltWhileLearningLocalizesAnotherRunWithThePreTrainedNet) {
  constexpr int kFrames = 70;
  const GeneratedWorld a("lab-room", synth::MotionKind::Robot, 1, kFrames);
  const GeneratedWorld c("lab-room", synth::MotionKind::Robot, 3, kFrames - 5);
  const auto map_path = testing::scratch_dir("saft_map") / "bs_saft_map.bsmap";
  struct RemoveAtExit {
    std::filesystem::path p;
    ~RemoveAtExit() {
      std::error_code ignored;
      std::filesystem::remove(p, ignored);
    }
  } cleanup{map_path};
  // Synchronous: every batch trained, so the map holds descriptors of many nets whatever the load.
  const SaftRun map_a = run(TumDataset::open(a.dir), SaftLearningMode::kContinuous, /*synchronous=*/true, 20, map_path);
  std::printf("map A (continuous SAFT): tracked %d/%d, ATE %.2f cm, %ld weight updates\n", map_a.tracked, kFrames,
              100 * map_a.ate_rmse, map_a.learning.weight_updates);
  ASSERT_GE(map_a.tracked, kFrames * 95 / 100);
  ASSERT_GE(map_a.learning.weight_updates, kFrames / 2);  // the map's descriptors really come from many nets
  const auto data_c = TumDataset::open(c.dir);
  SystemOptions so;
  so.mapping_thread = false;
  so.descriptor = DescriptorChoice::kSaft;  // offline: the shipped pre-trained weights
  System loc(data_c.settings(), so);
  loc.load_map(map_path);
  loc.set_mode(Mode::kLocalization);
  const std::size_t map_keyframes = loc.keyframe_count();
  int tracked = 0;
  long first = -1;
  for (std::size_t i = 0; i < data_c.size(); ++i) {
    const bool ok =
        loc.track_rgbd(data_c.load_rgb(i), data_c.load_depth(i), data_c.entry(i).timestamp).state == TrackingState::kOk;
    tracked += ok;
    if (ok && first < 0) first = static_cast<long>(i);
  }
  loc.shutdown();
  // C's poses in A's aligned frame: A's SLAM-to-truth transform, no new fit.
  const auto ate =
      absolute_trajectory_error(data_c.groundtruth(), transformed(loc.trajectory(), map_a.est_to_gt), Alignment::kNone).stats;
  const int n = static_cast<int>(data_c.size());
  std::printf("localize C (pre-trained SAFT): first tracked frame %ld, tracked %d/%d, ATE in A's frame %.2f cm\n", first,
              tracked, n, 100 * ate.rmse);
  EXPECT_GE(first, 0);
  EXPECT_LE(first, 10);
  EXPECT_GE(tracked, n * 95 / 100);
  EXPECT_LE(ate.rmse, 0.03);
  EXPECT_EQ(loc.keyframe_count(), map_keyframes);  // localization adds nothing
}

}  // namespace
}  // namespace builtscene::slam
