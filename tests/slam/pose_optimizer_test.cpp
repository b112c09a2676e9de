// Motion-only BA recovers a known pose from noisy 3D-2D / 3D-stereo matches with 30 % outliers.
#include <gtest/gtest.h>

#include "core/camera.hpp"
#include "slam/frame.hpp"
#include "slam/pose_optimizer.hpp"
#include "synthetic_scene.hpp"

namespace builtscene::slam {
namespace {

struct Case {
  bool stereo;
  const char* name;
  double disparity_sigma = 0;  // > 0: depth readings with this disparity noise, weighted by it
};

class PoseOptimizerRecovers : public ::testing::TestWithParam<Case> {};

TEST_P(PoseOptimizerRecovers, KnownPoseWith30PercentOutliers) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> ux(-2.0, 2.0), uz(1.0, 6.0), upx(0, 640), upy(0, 480);
  std::normal_distribution<double> noise(0, 1.0);
  auto K = test::kinect();
  K.disparity_sigma = GetParam().disparity_sigma;
  std::normal_distribution<double> disparity_noise(0, std::max(GetParam().disparity_sigma, 1e-9));
  const SE3 truth(so3_exp(Eigen::Vector3d(0.1, -0.2, 0.05)), Eigen::Vector3d(0.3, -0.1, 0.5));
  std::vector<Eigen::Vector3d> pts;
  std::vector<Observation> obs;
  std::vector<bool> is_outlier;
  const int n = 300;
  while (static_cast<int>(pts.size()) < n) {
    const Eigen::Vector3d pc(ux(rng), ux(rng) * 0.75, uz(rng));
    const Eigen::Vector2d uv = test::project(K, pc);
    if (uv.x() < 0 || uv.x() >= 640 || uv.y() < 0 || uv.y() >= 480) continue;
    pts.push_back(truth.inverse() * pc);
    Observation o;
    const bool outlier = pts.size() % 10 < 3;  // exactly 30 %
    if (outlier) {
      o.uv = {upx(rng), upy(rng)};
    } else {
      o.uv = uv + Eigen::Vector2d(noise(rng), noise(rng));
    }
    if (GetParam().stereo && K.disparity_sigma > 0)  // the depth reading's own error, apart from the pixel's
      o.u_right = o.uv.x() - (outlier ? K.bf / uz(rng) : K.bf / pc.z() + disparity_noise(rng));
    else if (GetParam().stereo)
      o.u_right = (outlier ? o.uv.x() - K.bf / uz(rng) : uv.x() - K.bf / pc.z() + noise(rng));
    if (GetParam().stereo && o.u_right < 0) o.u_right = 0;
    o.inv_sigma2 = 1.0;
    obs.push_back(o);
    is_outlier.push_back(outlier);
  }
  const SE3 start = test::perturb(truth, 5.0 * M_PI / 180.0, 0.10, rng);
  const auto r = optimize_pose(start, pts, obs, K);
  ASSERT_TRUE(r.ok);
  const double rot = test::rotation_error_deg(r.T_cw, truth), trans = test::translation_error(r.T_cw, truth);
  std::printf("%s: start error %.2f deg %.3f m -> %.4f deg %.4f m, %d inliers\n", GetParam().name,
              test::rotation_error_deg(start, truth), test::translation_error(start, truth), rot, trans, r.inliers);
  EXPECT_LT(rot, 0.1);
  EXPECT_LT(trans, 0.01);
  int true_pos = 0, false_pos = 0;
  for (std::size_t i = 0; i < obs.size(); ++i) {
    if (r.inlier[i] && !is_outlier[i]) ++true_pos;
    if (r.inlier[i] && is_outlier[i]) ++false_pos;
  }
  EXPECT_GE(true_pos, static_cast<int>(0.9 * 0.7 * n));  // chi2 at 95 % keeps ~95 % of inliers
  EXPECT_LE(false_pos, 3);                               // random pixels rarely fit
}

INSTANTIATE_TEST_SUITE_P(MonoAndStereo, PoseOptimizerRecovers,
                         ::testing::Values(Case{false, "mono"}, Case{true, "stereo"},
                                           Case{true, "disparity", 0.2}),
                         [](const auto& info) { return std::string(info.param.name); });

// The disparity form's chi-square, closed form: a point seen at its exact pixel whose depth
// reading implies a disparity off by delta costs (delta / sigma_d)^2, whatever the level.
TEST(PoseOptimizer, DisparityResidualIsWeightedByItsOwnSigma) {
  auto K = test::kinect();
  K.disparity_sigma = 0.25;
  const Eigen::Vector3d pc(0.4, -0.2, 2.5);
  const Eigen::Vector2d uv = test::project(K, pc);
  for (const double inv_sigma2 : {1.0, 1.0 / (1.2 * 1.2 * 1.2 * 1.2)}) {
    for (const double delta : {0.0, 0.1, 0.5}) {
      Observation o;
      o.uv = uv;
      o.inv_sigma2 = inv_sigma2;
      o.u_right = uv.x() - (K.bf / pc.z() + delta);
      EXPECT_NEAR(reprojection_chi2(K, o, pc), (delta / 0.25) * (delta / 0.25), 1e-9);
    }
  }
  // A pixel error still counts with the level's information, and not twice.
  Observation o;
  o.uv = uv + Eigen::Vector2d(1.5, 0);
  o.inv_sigma2 = 0.5;
  o.u_right = o.uv.x() - K.bf / pc.z();
  EXPECT_NEAR(reprojection_chi2(K, o, pc), 1.5 * 1.5 * 0.5, 1e-9);
}

// Global and local bundle adjustment weigh a depth reading by GlobalBADisparitySigma and
// LocalBADisparitySigma, tracking by DisparitySigma; 0 falls back to DisparitySigma, and
// ORB-SLAM's form (DisparitySigma 0) stays ORB-SLAM's form everywhere.
TEST(PoseOptimizer, BundleAdjustmentsTakeTheirOwnDisparitySigma) {
  RgbdCameraSettings s;
  s.camera.fx = s.camera.fy = 525;
  s.camera.cx = 319.5;
  s.camera.cy = 239.5;
  struct Row {
    double tracking, global, local, expect_tracking, expect_global, expect_local;
  };
  for (const Row& r : {Row{0.2, 0.1, 0.15, 0.2, 0.1, 0.15}, Row{0.2, 0.0, 0.0, 0.2, 0.2, 0.2},
                       Row{0.2, 0.0, 0.1, 0.2, 0.2, 0.1}, Row{0.0, 0.1, 0.1, 0.0, 0.0, 0.0}}) {
    s.disparity_sigma = r.tracking;
    s.global_ba_disparity_sigma = r.global;
    s.local_ba_disparity_sigma = r.local;
    const auto ctx = FrameContext::make(s, ScalePyramid::make(1.2f, 8), DescriptorMetric::orb());
    EXPECT_DOUBLE_EQ(intrinsics_of(*ctx).disparity_sigma, r.expect_tracking);
    EXPECT_DOUBLE_EQ(global_ba_intrinsics_of(*ctx).disparity_sigma, r.expect_global);
    EXPECT_DOUBLE_EQ(local_ba_intrinsics_of(*ctx).disparity_sigma, r.expect_local);
    EXPECT_DOUBLE_EQ(local_ba_intrinsics_of(*ctx).fx, 525);
  }
}

TEST(PoseOptimizer, TooFewMatchesLeavesPoseUntouched) {
  const SE3 start(so3_exp(Eigen::Vector3d(0.1, 0, 0)), Eigen::Vector3d(1, 2, 3));
  const auto r = optimize_pose(start, {Eigen::Vector3d(0, 0, 2)}, {Observation{}}, test::kinect());
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(r.T_cw.matrix().isApprox(start.matrix()));
}

// The motion prior, closed form at the limit: points at infinity (mono matches 10 km away)
// fix the rotation and say nothing about the translation, so the translation must come
// from the prior exactly, and the rotation from the points even with a prior turned 1 deg.
// `n` monocular matches 10 km in front of a camera at `truth`: they fix its rotation and say
// nothing about its translation.
void points_at_infinity(const SE3& truth, std::size_t n, unsigned seed, std::vector<Eigen::Vector3d>& pts,
                        std::vector<Observation>& obs) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(-1.0, 1.0);
  while (pts.size() < n) {
    const Eigen::Vector3d pc = Eigen::Vector3d(ux(rng), 0.75 * ux(rng), 1.5).normalized() * 1e4;
    Observation o;
    o.uv = test::project(test::kinect(), pc);
    o.inv_sigma2 = 1.0;
    pts.push_back(truth.inverse() * pc);
    obs.push_back(o);
  }
}

TEST(PoseOptimizer, APriorFixesWhatThePointsLeaveFreeAndNothingElse) {
  const auto K = test::kinect();
  const SE3 truth(so3_exp(Eigen::Vector3d(0.02, -0.1, 0.03)), Eigen::Vector3d(0.2, 0.05, -0.3));
  std::vector<Eigen::Vector3d> pts;
  std::vector<Observation> obs;
  points_at_infinity(truth, 100, 7, pts, obs);
  const Eigen::Vector3d offset(0.04, -0.03, 0.05);
  PoseOptimizerOptions o;
  o.prior_T_cw = SE3(so3_exp(Eigen::Vector3d(0, M_PI / 180.0, 0)), Eigen::Vector3d::Zero()) * truth;
  o.prior_T_cw = SE3(o.prior_T_cw->rotation(), truth.translation() + offset);
  o.prior_sigma_m = 0.01;
  o.prior_sigma_rad = 0.005;
  const auto r = optimize_pose(SE3(truth.rotation(), truth.translation() + Eigen::Vector3d(0.1, 0.1, 0.1)), pts, obs,
                               K, o);
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.inliers, 100);
  EXPECT_LT(test::rotation_error_deg(r.T_cw, truth), 0.01);
  // T_cw * T_prior^-1 has no translation left: t = R R_prior^T t_prior.
  const SE3 d = r.T_cw * o.prior_T_cw->inverse();
  EXPECT_LT(d.translation().norm(), 1e-3) << d.translation().transpose();
}

// Full-information priors (TrackingOptions::depth_prior_weight), closed form: points at
// infinity fix the rotation; one prior holds only t_x + t_y and t_z, another only t_x - t_y,
// each at a different translation, so the answer takes each combination from its own prior
// and the matrix's off-diagonal terms decide it.
TEST(PoseOptimizer, FullInformationPriorsHoldOnlyTheirDirections) {
  const auto K = test::kinect();
  const SE3 truth(so3_exp(Eigen::Vector3d(-0.03, 0.2, 0.01)), Eigen::Vector3d(0.1, -0.2, 0.4));
  std::vector<Eigen::Vector3d> pts;
  std::vector<Observation> obs;
  points_at_infinity(truth, 60, 11, pts, obs);
  const Eigen::Vector3d a(0.30, 0.10, -0.20), b(-0.10, 0.25, 0.70);  // the two priors' translations
  PosePrior pa{SE3(truth.rotation(), a), Eigen::Matrix<double, 6, 6>::Zero()};
  PosePrior pb{SE3(truth.rotation(), b), Eigen::Matrix<double, 6, 6>::Zero()};
  pa.sqrt_information(0, 3) = pa.sqrt_information(0, 4) = 100.0;  // t_x + t_y
  pa.sqrt_information(1, 5) = 100.0;                              // t_z
  pb.sqrt_information(0, 3) = 100.0;                              // t_x - t_y
  pb.sqrt_information(0, 4) = -100.0;
  PoseOptimizerOptions o;
  o.priors = {pa, pb};
  const auto r = optimize_pose(SE3(truth.rotation(), Eigen::Vector3d::Zero()), pts, obs, K, o);
  ASSERT_TRUE(r.ok);
  EXPECT_LT(test::rotation_error_deg(r.T_cw, truth), 0.01);
  const Eigen::Vector3d t = r.T_cw.translation();
  EXPECT_NEAR(t.x() + t.y(), a.x() + a.y(), 1e-4);
  EXPECT_NEAR(t.x() - t.y(), b.x() - b.y(), 1e-4);
  EXPECT_NEAR(t.z(), a.z(), 1e-4);
}

}  // namespace
}  // namespace builtscene::slam
