#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "../common/run_cli.hpp"
#include "../common/scratch_dir.hpp"
#include "core/errors.hpp"
#include "eval/trajectory_error.hpp"
#include "eval/umeyama.hpp"

namespace builtscene {
namespace {

namespace fs = std::filesystem;

// A helical ground-truth trajectory at 30 Hz.
Trajectory helix(int n) {
  Trajectory t;
  for (int i = 0; i < n; ++i) {
    const double a = 0.05 * i;
    t.push_back({1000.0 + i / 30.0,
                 SE3(Eigen::Quaterniond(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ())),
                     Eigen::Vector3d(2.0 * std::cos(a), 1.5 * std::sin(a), 0.02 * i))});
  }
  return t;
}

// Noise with zero mean and zero cross-covariance with the (centred) positions: the optimal
// alignment is then exactly the applied transform and the ATE is exactly the noise's RMS.
std::vector<Eigen::Vector3d> orthogonal_noise(const std::vector<Eigen::Vector3d>& pos, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, sigma);
  const std::size_t n = pos.size();
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : pos) mean += p;
  mean /= static_cast<double>(n);
  std::vector<Eigen::Vector3d> noise(n);
  for (auto& v : noise) v = {g(rng), g(rng), g(rng)};
  Eigen::Vector3d nm = Eigen::Vector3d::Zero();
  for (const auto& v : noise) nm += v;
  nm /= static_cast<double>(n);
  Eigen::Matrix3d NA = Eigen::Matrix3d::Zero(), AA = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    noise[i] -= nm;
    NA += noise[i] * (pos[i] - mean).transpose();
    AA += (pos[i] - mean) * (pos[i] - mean).transpose();
  }
  const Eigen::Matrix3d M = NA * AA.inverse();
  for (std::size_t i = 0; i < n; ++i) noise[i] -= M * (pos[i] - mean);
  return noise;
}

// The estimate is the ground truth seen through `gt_to_est`, plus `noise` in the gt frame.
Trajectory make_estimate(const Trajectory& gt, const Sim3& gt_to_est, const std::vector<Eigen::Vector3d>& noise) {
  Trajectory est;
  for (std::size_t i = 0; i < gt.size(); ++i) {
    SE3 p(gt[i].pose.rotation(), gt[i].pose.translation() + noise[i]);
    est.push_back({gt[i].timestamp + 0.004, gt_to_est.transform_pose(p)});
  }
  return est;
}

double rms(const std::vector<Eigen::Vector3d>& v) {
  double s = 0;
  for (const auto& x : v) s += x.squaredNorm();
  return std::sqrt(s / static_cast<double>(v.size()));
}

TEST(Ate, RigidTransformWithOrthogonalNoiseGivesNoiseRms) {
  const Trajectory gt = helix(300);
  std::vector<Eigen::Vector3d> pos;
  for (const auto& p : gt) pos.push_back(p.pose.translation());
  const auto noise = orthogonal_noise(pos, 0.03, 7);
  const Sim3 T(Eigen::Quaterniond(Eigen::AngleAxisd(1.2, Eigen::Vector3d(1, -2, 0.5).normalized())),
               Eigen::Vector3d(5, -3, 2), 1.0);
  const auto r = absolute_trajectory_error(gt, make_estimate(gt, T, noise), Alignment::kSE3);
  EXPECT_EQ(r.stats.count, 300u);
  EXPECT_NEAR(r.stats.rmse, rms(noise), 1e-6);
  EXPECT_LT((r.est_to_gt.matrix() - T.inverse().matrix()).norm(), 1e-6);
}

TEST(Ate, SimilarityTransformRecoveredWithSim3) {
  const Trajectory gt = helix(200);
  std::vector<Eigen::Vector3d> pos;
  for (const auto& p : gt) pos.push_back(p.pose.translation());
  const auto noise = orthogonal_noise(pos, 0.01, 8);
  const Sim3 T(Eigen::Quaterniond(Eigen::AngleAxisd(-0.4, Eigen::Vector3d::UnitX())), Eigen::Vector3d(0, 1, 0), 0.37);
  const auto est = make_estimate(gt, T, noise);
  const auto r = absolute_trajectory_error(gt, est, Alignment::kSim3);
  // Closed form: with centred positions a_i and orthogonal noise n_i the least-squares scale
  // shrinks by k = var(a) / (var(a) + var(n)) and the residual is (1-k) a_i - k n_i.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : pos) mean += p;
  mean /= static_cast<double>(pos.size());
  double va = 0;
  for (const auto& p : pos) va += (p - mean).squaredNorm();
  va /= static_cast<double>(pos.size());
  const double vn = rms(noise) * rms(noise);
  const double k = va / (va + vn);
  EXPECT_NEAR(r.est_to_gt.scale(), k / 0.37, 1e-9);
  EXPECT_NEAR(r.stats.rmse, std::sqrt((1 - k) * (1 - k) * va + k * k * vn), 1e-6);
  // Without scale the error must be large: a 0.37 scale over a 4 m helix.
  EXPECT_GT(absolute_trajectory_error(gt, est, Alignment::kSE3).stats.rmse, 0.5);
}

TEST(Ate, NoAlignmentMeasuresRawDifference) {
  const Trajectory gt = helix(50);
  Trajectory est = gt;
  for (auto& p : est) p.pose = SE3(p.pose.rotation(), p.pose.translation() + Eigen::Vector3d(0.3, 0.4, 0));
  const auto r = absolute_trajectory_error(gt, est, Alignment::kNone);
  EXPECT_NEAR(r.stats.rmse, 0.5, 1e-12);
  EXPECT_NEAR(r.stats.max, 0.5, 1e-12);
}

TEST(Ate, NoOverlapIsInputError) {
  Trajectory gt = helix(10), est = helix(10);
  for (auto& p : est) p.timestamp += 100;
  EXPECT_THROW(absolute_trajectory_error(gt, est, Alignment::kSE3), InputError);
}

TEST(Rpe, ConstantDriftPerStepIsMeasured) {
  // Estimate drifts 1 cm along the world x axis per frame: the relative-motion error over
  // delta 5 is gt_5^-1 * shift(5 cm) * gt_5, a pure translation of exactly 5 cm.
  const Trajectory gt = helix(100);
  Trajectory est;
  for (std::size_t i = 0; i < gt.size(); ++i)
    est.push_back({gt[i].timestamp, SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.01 * i, 0, 0)) * gt[i].pose});
  const auto r = relative_pose_error(gt, est, 5);
  EXPECT_NEAR(r.translation.rmse, 0.05, 1e-9);
  EXPECT_NEAR(r.rotation.max, 0.0, 1e-6);
  EXPECT_EQ(r.translation.count, 95u);
}

// Second tool: an independent numpy implementation on real ground truth.
TEST(AteCli, MatchesIndependentNumpyReferenceOnRealGroundTruth) {
  const auto gt_path = testing::shared_data() / "7scenes-kitchen" / "groundtruth.txt";
  if (!fs::exists(gt_path)) GTEST_SKIP() << "../shared/data/7scenes-kitchen is absent";
  const Trajectory gt = read_tum_trajectory(gt_path);
  std::vector<Eigen::Vector3d> noise;
  std::mt19937 rng(9);
  std::normal_distribution<double> g(0.0, 0.02);
  for (std::size_t i = 0; i < gt.size(); ++i) noise.emplace_back(g(rng), g(rng), g(rng));
  const Sim3 T(Eigen::Quaterniond(Eigen::AngleAxisd(2.0, Eigen::Vector3d(0.3, 1, -0.2).normalized())),
               Eigen::Vector3d(-1, 7, 0.5), 1.7);
  const auto dir = testing::scratch_dir("ate_real");
  write_tum_trajectory(dir / "est.txt", make_estimate(gt, T, noise));
  for (const std::string align : {"se3", "sim3"}) {
    const auto ours = testing::run_cli("eval ate --json --align " + align + " --gt " + testing::shell_quote(gt_path) +
                                       " --est " + testing::shell_quote(dir / "est.txt"));
    ASSERT_EQ(ours.exit_code, 0) << ours.err;
    const auto reference = testing::run_cli_command(
        "/usr/bin/python3 " + testing::shell_quote(testing::source_dir() / "tests/eval/ate_reference.py") + " " +
        testing::shell_quote(gt_path) + " " + testing::shell_quote(dir / "est.txt") + (align == "sim3" ? " --sim3" : ""));
    ASSERT_EQ(reference.exit_code, 0) << reference.err;
    const auto a = nlohmann::json::parse(ours.out), b = nlohmann::json::parse(reference.out);
    EXPECT_EQ(a["pairs"].get<int>(), b["pairs"].get<int>());
    for (const char* key : {"rmse", "mean", "median", "max"})
      EXPECT_NEAR(a[key].get<double>(), b[key].get<double>(), 1e-6) << align << " " << key;
    if (align == "sim3") {
      EXPECT_NEAR(a["scale"].get<double>(), b["scale"].get<double>(), 1e-6);
    }
  }
}

}  // namespace
}  // namespace builtscene

namespace builtscene {
namespace {

// --aligned-out: a noise-free estimate that is a rigid motion of the ground truth comes back
// onto the ground truth, pose for pose (rotation and position).
TEST(AteCli, AlignedOutputLandsOnTheGroundTruth) {
  Trajectory gt;
  for (int i = 0; i < 50; ++i) {
    const double a = 0.1 * i;
    gt.push_back({0.1 * i, SE3(Eigen::Quaterniond(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ())),
                               Eigen::Vector3d(std::cos(a), std::sin(2 * a), 0.1 * a))});
  }
  const Sim3 T(Eigen::Quaterniond(Eigen::AngleAxisd(1.1, Eigen::Vector3d(1, 2, 3).normalized())),
               Eigen::Vector3d(4, -2, 1), 1.0);
  const std::vector<Eigen::Vector3d> no_noise(gt.size(), Eigen::Vector3d::Zero());
  const auto dir = testing::scratch_dir("ate_aligned");
  write_tum_trajectory(dir / "gt.txt", gt);
  write_tum_trajectory(dir / "est.txt", make_estimate(gt, T, no_noise));
  const auto r = testing::run_cli("eval ate --json --gt " + testing::shell_quote(dir / "gt.txt") + " --est " +
                                  testing::shell_quote(dir / "est.txt") + " --aligned-out " +
                                  testing::shell_quote(dir / "aligned.txt"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Trajectory aligned = read_tum_trajectory(dir / "aligned.txt");
  ASSERT_EQ(aligned.size(), gt.size());
  for (std::size_t i = 0; i < gt.size(); ++i) {
    EXPECT_LT((aligned[i].pose.translation() - gt[i].pose.translation()).norm(), 1e-5) << i;
    EXPECT_LT(aligned[i].pose.rotation().angularDistance(gt[i].pose.rotation()), 1e-5) << i;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace builtscene
