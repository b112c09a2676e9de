// Local BA on a constructed configuration with known truth: cameras on an arc looking at a
// cloud of points; the first two cameras fixed (the gauge); the others and the points
// perturbed; noisy and partly wrong measurements.
#include <gtest/gtest.h>

#include <random>

#include "core/so3.hpp"
#include "slam/local_bundle_adjuster.hpp"
#include "synthetic_scene.hpp"

namespace builtscene::slam {
namespace {

// A camera with no point of its own is held by two relative-pose terms (depth links) that
// disagree: the first is sure of the slide along x, the second of the slide along y (each
// along its own left increment, in the first camera's rotated frame). The camera ends where
// each term is sure: 0 along x, 0.2 m along y, whatever its start. A term read as a right
// increment would swap x and y here (the measurement turns 90 degrees about z).
TEST(LocalBundleAdjuster, RelativePoseTermsHoldACameraAlongTheirInformation) {
  BundleAdjustmentProblem pb;
  pb.K = test::kinect();
  const SE3 A(so3_exp(Eigen::Vector3d(0, 0, M_PI / 2)), Eigen::Vector3d(0.3, -0.1, 0.5));  // T_10
  const SE3 B = SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.1, 0.2, 0)) * A;
  std::mt19937 rng(5);
  pb.cameras.push_back({SE3(), true});
  pb.cameras.push_back({test::perturb(A, 0.05, 0.1, rng), false});
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector3d p(u(rng), u(rng), 3 + u(rng));
    pb.points.push_back(p);
    BundleAdjustmentProblem::Measurement m;
    m.camera = 0;
    m.point = i;
    m.o.uv = test::project(pb.K, p);
    m.o.inv_sigma2 = 1.0;
    pb.measurements.push_back(m);
  }
  Eigen::Matrix<double, 6, 6> sure_x = Eigen::Matrix<double, 6, 6>::Identity(), sure_y = sure_x;
  sure_x(0, 0) = 1e4;
  sure_y(1, 1) = 1e4;
  pb.relative_poses.push_back({1, 0, A, sure_x});
  pb.relative_poses.push_back({1, 0, B, sure_y});
  const auto r = solve_bundle_adjustment(pb, {20, 20});
  ASSERT_TRUE(r.solved);
  const SE3 d = r.poses[1] * A.inverse();  // the camera's left increment from A
  EXPECT_NEAR(d.translation().x(), 0.0, 1e-3);
  EXPECT_NEAR(d.translation().y(), 0.2, 1e-3);
  EXPECT_NEAR(d.translation().z(), 0.0, 1e-3);
  EXPECT_LT(so3_log(d.rotation()).norm(), 1e-3);
}

TEST(LocalBundleAdjuster, LowersErrorAndRecoversPerturbedPoses) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.5, 1.5), uz(2.0, 5.0), unit(0, 1);
  std::normal_distribution<double> noise(0, 0.7), pn(0, 1);
  BundleAdjustmentProblem pb;
  pb.K = test::kinect();
  std::vector<SE3> truth;
  for (int c = 0; c < 8; ++c) {
    // Camera centre moves along x, yaw turning slightly towards the cloud centre.
    const double x = -0.6 + 0.15 * c;
    const Eigen::Quaterniond R_wc = so3_exp(Eigen::Vector3d(0, -0.08 * (c - 4), 0));
    const SE3 T_wc(R_wc, Eigen::Vector3d(x, 0.05 * std::sin(c), 0));
    truth.push_back(T_wc.inverse());
  }
  std::vector<Eigen::Vector3d> points_truth;
  for (int i = 0; i < 400; ++i) points_truth.emplace_back(u(rng), u(rng) * 0.7, uz(rng));

  for (std::size_t c = 0; c < truth.size(); ++c)
    pb.cameras.push_back({c < 2 ? truth[c] : test::perturb(truth[c], 1.5 * M_PI / 180.0, 0.05, rng), c < 2});
  for (const auto& p : points_truth) pb.points.push_back(p + 0.03 * Eigen::Vector3d(pn(rng), pn(rng), pn(rng)));
  int outliers = 0;
  for (std::size_t c = 0; c < truth.size(); ++c) {
    for (std::size_t i = 0; i < points_truth.size(); ++i) {
      const Eigen::Vector3d pc = truth[c] * points_truth[i];
      const Eigen::Vector2d uv = test::project(pb.K, pc);
      if (pc.z() <= 0.1 || uv.x() < 0 || uv.x() >= 640 || uv.y() < 0 || uv.y() >= 480) continue;
      BundleAdjustmentProblem::Measurement m;
      m.camera = static_cast<int>(c);
      m.point = static_cast<int>(i);
      m.o.uv = uv + Eigen::Vector2d(noise(rng), noise(rng));
      if (unit(rng) < 0.05) {
        m.o.uv += Eigen::Vector2d(40 + 40 * unit(rng), -30);  // gross outlier
        ++outliers;
      }
      if (i % 2 == 0) m.o.u_right = uv.x() - pb.K.bf / pc.z() + noise(rng);  // half with depth
      m.o.inv_sigma2 = 1.0;
      pb.measurements.push_back(m);
    }
  }
  ASSERT_GT(pb.measurements.size(), 2000u);

  const auto r = solve_bundle_adjustment(pb);
  ASSERT_TRUE(r.solved);
  std::printf("RMS reprojection %.2f px -> %.2f px (inliers), %d planted outliers\n", r.initial_rms_px, r.final_rms_px,
              outliers);
  EXPECT_LT(r.final_rms_px, 1.5);
  EXPECT_LT(r.final_rms_px, 0.2 * r.initial_rms_px);
  for (std::size_t c = 0; c < truth.size(); ++c) {
    const double before = test::translation_error(pb.cameras[c].T_cw, truth[c]);
    const double after = test::translation_error(r.poses[c], truth[c]);
    const double rot_after = test::rotation_error_deg(r.poses[c], truth[c]);
    if (c < 2) {
      EXPECT_LT(after, 1e-12) << "fixed camera moved";
      continue;
    }
    std::printf("camera %zu: centre error %.4f m -> %.4f m, rotation error %.3f deg\n", c, before, after, rot_after);
    EXPECT_LT(after, 0.005);
    EXPECT_LT(rot_after, 0.1);
  }
  int flagged = 0;
  for (bool in : r.measurement_inlier) flagged += !in;
  EXPECT_GE(flagged, outliers * 9 / 10);
}

TEST(LocalBundleAdjuster, AbortStopsEarlyWithoutCrashing) {
  BundleAdjustmentProblem pb;
  pb.K = test::kinect();
  pb.cameras.push_back({SE3(), false});
  pb.points.emplace_back(0, 0, 2);
  pb.measurements.push_back({0, 0, Observation{Eigen::Vector2d(320, 240), -1, 1}});
  std::atomic<bool> abort{true};
  const auto r = solve_bundle_adjustment(pb, {}, &abort);
  EXPECT_TRUE(r.aborted);
  const auto empty = solve_bundle_adjustment(BundleAdjustmentProblem{});
  EXPECT_FALSE(empty.solved);
}

}  // namespace
}  // namespace builtscene::slam
