// The SAFT network and its inputs: the patch sampler against an independently rotated image,
// keypoint warping against known homographies, the layer arithmetic, the weights file round
// trip and its error handling, and patch verification on generated images where the true
// answer is known (identical images: every matching distance is zero).
#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/errors.hpp"
#include "features/descriptor_roc.hpp"
#include "features/keypoint_warp.hpp"
#include "features/orb_extractor.hpp"
#include "features/patch_verification.hpp"
#include "features/saft_extractor.hpp"
#include "features/saft_network.hpp"
#include "features/saft_patch.hpp"
#include "test_images.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene {
namespace {

// The pyramid of a single image (level 0 only).
const ScalePyramid kOneLevel = ScalePyramid::make(1.2f, 1);

namespace fs = std::filesystem;

fs::path temp_dir(const std::string& name) { return testing::scratch_dir("saft_" + name); }

TEST(SaftPatch, RotatedKeypointSeesTheRotatedImage) {
  const cv::Mat img = test::textured_image(200, 160, 5);
  cv::Mat rotated;  // 90 degrees clockwise: (x, y) -> (H - 1 - y, x)
  cv::rotate(img, rotated, cv::ROTATE_90_CLOCKWISE);
  cv::KeyPoint a(cv::Point2f(90, 70), 31, 0.0f, 0, 0);
  cv::KeyPoint b(cv::Point2f(160 - 1 - 70, 90), 31, 90.0f, 0, 0);
  const cv::Mat pa = sample_saft_patches({img}, kOneLevel, {a});
  const cv::Mat pb = sample_saft_patches({rotated}, kOneLevel, {b});
  double max_diff = 0;
  cv::minMaxLoc(cv::abs(cv::Mat_<int>(pa) - cv::Mat_<int>(pb)), nullptr, &max_diff);
  EXPECT_LE(max_diff, 1.0);
  // And the unrotated patch is the plain crop centred on the keypoint.
  const cv::Mat crop = img(cv::Rect(90 - 15, 70 - 15, 32, 32)).clone();
  const cv::Mat shifted = sample_saft_patches({img}, kOneLevel, {cv::KeyPoint(cv::Point2f(90.5f, 70.5f), 31, 0.0f, 0, 0)});
  EXPECT_EQ(cv::norm(crop.reshape(1, 1), shifted, cv::NORM_INF), 0.0);
}

TEST(SaftPatch, NormalizedRowsHaveZeroMeanUnitStd) {
  const cv::Mat img = test::textured_image(200, 160, 6);
  const cv::Mat p = normalize_saft_patches(sample_saft_patches({img}, kOneLevel, {cv::KeyPoint(cv::Point2f(100, 80), 31, 33.0f, 0, 0)}));
  cv::Scalar mean, stddev;
  cv::meanStdDev(p, mean, stddev);
  EXPECT_NEAR(mean[0], 0.0, 1e-4);
  EXPECT_NEAR(stddev[0], 1.0, 1e-3);
  // A flat patch stays zero instead of dividing by zero.
  const cv::Mat flat = normalize_saft_patches(cv::Mat(1, kSaftPatchPixels, CV_8U, cv::Scalar(77)));
  EXPECT_EQ(cv::countNonZero(flat), 0);
}

TEST(KeypointWarp, ScaleAndLevelFollowTheHomography) {
  const ScalePyramid pyr = ScalePyramid::make(1.2f, 8);
  const double s = 1.2 * 1.2;
  const cv::Matx33d zoom(s, 0, 10, 0, s, 20, 0, 0, 1);
  EXPECT_NEAR(homography_local_scale(zoom, {100, 100}), s, 1e-12);
  const double a = 0.7;
  const cv::Matx33d rot(std::cos(a), -std::sin(a), 300, std::sin(a), std::cos(a), 50, 0, 0, 1);
  EXPECT_NEAR(homography_local_scale(rot, {40, 80}), 1.0, 1e-12);
  cv::KeyPoint kp(cv::Point2f(200, 150), 31, 0, 0, 1);
  const auto m = warp_keypoint(zoom, kp, pyr, cv::Size(1000, 1000), 16);
  ASSERT_TRUE(m.has_value());
  EXPECT_EQ(m->octave, 3);
  EXPECT_NEAR(m->pt.x, 200 * s + 10, 1e-3);
  EXPECT_NEAR(m->pt.y, 150 * s + 20, 1e-3);
  // Outside the second image, or a level beyond the pyramid: no keypoint.
  EXPECT_FALSE(warp_keypoint(zoom, kp, pyr, cv::Size(300, 300), 16).has_value());
  const cv::Matx33d huge(8, 0, 0, 0, 8, 0, 0, 0, 1);
  EXPECT_FALSE(warp_keypoint(huge, cv::KeyPoint(cv::Point2f(10, 10), 31, 0, 0, 7), pyr, cv::Size(10000, 10000), 16).has_value());
}

TEST(SaftNetwork, MultiplyAddsFromTheLayerShapes) {
  // conv 1->8 at 32x32, 8->16 at 16x16, 16->32 at 8x8, 32->64 at 4x4 (3x3 kernels), then 1024 -> 64.
  const long expected = 32 * 32 * 8 * 1 * 9 + 16 * 16 * 16 * 8 * 9 + 8 * 8 * 32 * 16 * 9 + 4 * 4 * 64 * 32 * 9 + 1024 * 64;
  EXPECT_EQ(SaftNetwork::multiply_adds_per_patch(), expected);
  EXPECT_LE(SaftNetwork::multiply_adds_per_patch(), 1100000);
}

TEST(SaftNetwork, UnitRowsBatchIndependentAndRoundTrip) {
  const cv::Mat img = test::textured_image(320, 240, 7);
  OrbExtractor orb;
  std::vector<cv::KeyPoint> kps;
  cv::Mat d;
  orb.extract(img, kps, d);
  ASSERT_GT(kps.size(), 150u);
  const cv::Mat patches = normalize_saft_patches(sample_saft_patches(orb.levels(), orb.pyramid(), kps));
  SaftNetworkOptions small;
  small.batch_size = 16;
  SaftNetwork net(small, 3);
  cv::Mat unit, raw;
  net.describe(patches, unit, &raw);
  ASSERT_EQ(unit.rows, patches.rows);
  ASSERT_EQ(unit.cols, SaftNetwork::kDimension);
  for (int r = 0; r < unit.rows; ++r) {
    EXPECT_NEAR(cv::norm(unit.row(r)), 1.0, 1e-4);
    EXPECT_NEAR(cv::norm(raw.row(r) / cv::norm(raw.row(r)) - unit.row(r)), 0.0, 1e-4);
  }
  // One patch alone (padded batch) gives the same row as inside a full batch.
  cv::Mat one;
  net.describe(patches.row(37).clone(), one);
  EXPECT_LT(cv::norm(one - unit.row(37)), 1e-5);

  const fs::path dir = temp_dir("weights");
  net.save(dir / "w.saft");
  EXPECT_LT(fs::file_size(dir / "w.saft"), 1u << 20);
  EXPECT_EQ(static_cast<long>(fs::file_size(dir / "w.saft")), 8 + 12 + 4 * (net.parameter_count() + 22));
  SaftNetwork loaded = SaftNetwork::load(dir / "w.saft");
  cv::Mat unit2;
  loaded.describe(patches, unit2);
  EXPECT_LT(cv::norm(unit2 - unit, cv::NORM_INF), 1e-5);
  // A differently seeded network describes differently (the load did something).
  SaftNetwork other(small, 4);
  cv::Mat unit3;
  other.describe(patches, unit3);
  EXPECT_GT(cv::norm(unit3 - unit, cv::NORM_INF), 1e-2);
  fs::remove_all(dir);
}

TEST(SaftNetwork, BadWeightsFilesAreInputErrors) {
  const fs::path dir = temp_dir("bad");
  EXPECT_THROW(SaftNetwork::load(dir / "missing.saft"), InputError);
  {
    std::ofstream(dir / "text.saft") << "not weights at all";
  }
  EXPECT_THROW(SaftNetwork::load(dir / "text.saft"), InputError);
  SaftNetwork net;
  net.save(dir / "good.saft");
  const auto size = fs::file_size(dir / "good.saft");
  fs::copy_file(dir / "good.saft", dir / "short.saft");
  fs::resize_file(dir / "short.saft", size - 100);
  EXPECT_THROW(SaftNetwork::load(dir / "short.saft"), InputError);
  fs::copy_file(dir / "good.saft", dir / "long.saft");
  {
    std::ofstream(dir / "long.saft", std::ios::app | std::ios::binary) << "xx";
  }
  EXPECT_THROW(SaftNetwork::load(dir / "long.saft"), InputError);
  fs::remove_all(dir);
}

TEST(PatchVerification, IdenticalImagesGiveZeroMatchingDistancesAndFpr95Zero) {
  const fs::path dir = temp_dir("seq");
  const cv::Mat img = test::textured_image(480, 360, 9);
  cv::imwrite((dir / "1.png").string(), img);
  cv::imwrite((dir / "2.png").string(), img);
  std::ofstream(dir / "H_1_2") << "1 0 0\n0 1 0\n0 0 1\n";
  const HomographySequence seq = read_homography_sequence(dir);
  ASSERT_EQ(seq.targets.size(), 1u);
  SaftNetwork net;
  const PatchVerificationDistances d = verify_patches(seq, net, {});
  ASSERT_GT(d.orb_pos.size(), 100u);
  EXPECT_EQ(d.orb_neg.size(), d.orb_pos.size());
  for (double x : d.orb_pos) EXPECT_EQ(x, 0.0);
  for (double x : d.saft_pos) EXPECT_LT(x, 1e-3);
  EXPECT_EQ(fpr_at_tpr(d.orb_pos, d.orb_neg).fpr, 0.0);
  EXPECT_EQ(fpr_at_tpr(d.saft_pos, d.saft_neg).fpr, 0.0);
  fs::remove_all(dir);
}

TEST(PatchVerification, KnownRotationKeepsOrbMatchesClose) {
  // 2.png is 1.png rotated 90 degrees: ORB's orientation makes the patches the same up to
  // resampling, so matching Hamming distances stay far below non-matching ones.
  const fs::path dir = temp_dir("rot");
  const cv::Mat img = test::textured_image(400, 400, 10);
  cv::Mat rotated;
  cv::rotate(img, rotated, cv::ROTATE_90_CLOCKWISE);
  cv::imwrite((dir / "1.png").string(), img);
  cv::imwrite((dir / "2.png").string(), rotated);
  std::ofstream(dir / "H_1_2") << "0 -1 399\n1 0 0\n0 0 1\n";
  SaftNetwork net;
  const PatchVerificationDistances d = verify_patches(read_homography_sequence(dir), net, {});
  ASSERT_GT(d.orb_pos.size(), 100u);
  EXPECT_LT(fpr_at_tpr(d.orb_pos, d.orb_neg).fpr, 0.05);
  fs::remove_all(dir);
}

TEST(PatchVerification, MalformedSequencesAreInputErrors) {
  const fs::path dir = temp_dir("malformed");
  EXPECT_THROW(read_homography_sequence(dir / "nope"), InputError);
  EXPECT_THROW(read_homography_sequence(dir), InputError);  // no 1.png
  cv::imwrite((dir / "1.png").string(), test::textured_image(100, 100, 1));
  EXPECT_THROW(read_homography_sequence(dir), InputError);  // no 2.png
  cv::imwrite((dir / "2.png").string(), test::textured_image(100, 100, 2));
  EXPECT_THROW(read_homography_sequence(dir), InputError);  // no H_1_2
  std::ofstream(dir / "H_1_2") << "1 0 0 0 1";
  EXPECT_THROW(read_homography_sequence(dir), InputError);
  std::ofstream(dir / "H_1_2") << "1 0 0 0 1 0 0 0 nan";
  EXPECT_THROW(read_homography_sequence(dir), InputError);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace builtscene
