// ORB against a known image transformation: the second image is the first rotated and scaled
// by a known similarity, so every correct match must land where the homography says.
#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "features/descriptor.hpp"
#include "features/keypoint_distribution.hpp"
#include "features/orb_extractor.hpp"
#include "test_images.hpp"

namespace builtscene {
namespace {

struct MatchStats {
  int matches = 0;
  int correct = 0;
  double precision() const { return matches ? static_cast<double>(correct) / matches : 0.0; }
};

// Mutual nearest neighbours by Hamming distance (< 64), correct when the keypoint of image 2
// lies within 4 px of the first keypoint mapped by H.
MatchStats evaluate(const std::vector<cv::KeyPoint>& k1, const cv::Mat& d1, const std::vector<cv::KeyPoint>& k2,
                    const cv::Mat& d2, const cv::Mat& H) {
  const auto metric = DescriptorMetric::orb();
  const auto fwd = match_brute_force(d1, d2, metric, 64.0f, 1.0f);
  const auto bwd = match_brute_force(d2, d1, metric, 1e9f, 1.0f);
  MatchStats s;
  for (std::size_t i = 0; i < fwd.size(); ++i) {
    const int j = fwd[i];
    if (j < 0 || bwd[static_cast<std::size_t>(j)] != static_cast<int>(i)) continue;
    ++s.matches;
    std::vector<cv::Point2f> in{k1[i].pt}, out;
    cv::perspectiveTransform(in, out, H);
    if (cv::norm(out[0] - k2[static_cast<std::size_t>(j)].pt) < 4.0) ++s.correct;
  }
  return s;
}

class OrbUnderSimilarity : public ::testing::TestWithParam<std::pair<double, double>> {};

TEST_P(OrbUnderSimilarity, MatchesLandWhereTheHomographySays) {
  const auto [angle_deg, scale] = GetParam();
  // Both images are 480 x 480 crops from the centre of one large texture, the second after
  // rotating and scaling the texture about its centre, so the two views overlap fully and
  // H (crop 1 -> crop 2) is known exactly.
  const cv::Mat big = test::textured_image(1200, 1200, 7);
  const cv::Rect crop(360, 360, 480, 480);
  const cv::Mat A = cv::getRotationMatrix2D(cv::Point2f(600, 600), angle_deg, scale);
  cv::Mat warped;
  cv::warpAffine(big, warped, A, big.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(128));
  const cv::Mat img1 = big(crop).clone(), img2 = warped(crop).clone();
  cv::Mat Abig = cv::Mat::eye(3, 3, CV_64F), shift = cv::Mat::eye(3, 3, CV_64F), unshift = cv::Mat::eye(3, 3, CV_64F);
  A.copyTo(Abig.rowRange(0, 2));
  shift.at<double>(0, 2) = shift.at<double>(1, 2) = 360;
  unshift.at<double>(0, 2) = unshift.at<double>(1, 2) = -360;
  const cv::Mat H = unshift * Abig * shift;

  OrbExtractor orb;
  std::vector<cv::KeyPoint> k1, k2;
  cv::Mat d1, d2;
  orb.extract(img1, k1, d1);
  orb.extract(img2, k2, d2);
  ASSERT_GT(k1.size(), 900u);
  ASSERT_GT(k2.size(), 700u);
  const MatchStats s = evaluate(k1, d1, k2, d2, H);
  // Reference: OpenCV's ORB on the same pair with the same matching rule.
  auto cv_orb = cv::ORB::create(1000);
  std::vector<cv::KeyPoint> c1, c2;
  cv::Mat e1, e2;
  cv_orb->detectAndCompute(img1, cv::noArray(), c1, e1);
  cv_orb->detectAndCompute(img2, cv::noArray(), c2, e2);
  const MatchStats r = evaluate(c1, e1, c2, e2, H);
  std::printf("rotation %.0f deg, scale %.2f: ours %d/%d correct (%.3f), cv::ORB %d/%d (%.3f)\n", angle_deg, scale,
              s.correct, s.matches, s.precision(), r.correct, r.matches, r.precision());
  // Mutual nearest neighbours are mostly right and plentiful. OpenCV's ORB (learned BRIEF
  // pattern, Harris-ranked keypoints concentrated on the strongest corners) is printed for
  // reference; ours trades some of its matches for the even spread that tracking needs.
  EXPECT_GT(s.precision(), 0.75);
  EXPECT_GT(s.correct, 200);
}

INSTANTIATE_TEST_SUITE_P(RotationsAndScales, OrbUnderSimilarity,
                         ::testing::Values(std::make_pair(0.0, 1.0), std::make_pair(30.0, 1.0), std::make_pair(90.0, 1.0),
                                           std::make_pair(0.0, 1.3), std::make_pair(45.0, 1.25), std::make_pair(-60.0, 0.8)));

TEST(OrbExtractor, RespectsBudgetAndLevels) {
  OrbExtractorOptions o;
  o.n_features = 500;
  OrbExtractor orb(o);
  std::vector<cv::KeyPoint> k;
  cv::Mat d;
  orb.extract(test::textured_image(640, 480, 3), k, d);
  EXPECT_LE(k.size(), 500u);
  EXPECT_GT(k.size(), 450u);
  ASSERT_EQ(d.rows, static_cast<int>(k.size()));
  EXPECT_EQ(d.cols, 32);
  int max_octave = 0;
  for (const auto& kp : k) {
    EXPECT_GE(kp.pt.x, 0);
    EXPECT_LT(kp.pt.x, 640);
    EXPECT_GE(kp.pt.y, 0);
    EXPECT_LT(kp.pt.y, 480);
    max_octave = std::max(max_octave, kp.octave);
  }
  EXPECT_EQ(max_octave, 7);
}

// Where a pixel of a coarse level lies in the image. Truth: Gaussian spots drawn at known
// sub-pixel positions; on each level of the extractor's own pyramid, a spot's intensity
// centroid, mapped back with to_image, must land on the drawn position. Plain multiplication
// by the level's scale (ORB-SLAM's rule) misses by 0.5 (scale - 1) px per axis plus the
// level's size rounding: 0.1 px on level 1, 1.3 px on level 7.
TEST(OrbExtractor, CoarseLevelPixelsMapBackToWhereTheyWereFound) {
  const int W = 640, H = 480;
  const std::vector<cv::Point2d> spots = {{100.3, 90.7}, {320.0, 240.0}, {555.6, 123.4}, {211.1, 400.9}, {470.5, 350.25}};
  const double sigma = 9.0;  // px; still several pixels wide on level 7
  cv::Mat img(H, W, CV_8UC1);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      double v = 20;
      for (const auto& c : spots) v += 220 * std::exp(-((x - c.x) * (x - c.x) + (y - c.y) * (y - c.y)) / (2 * sigma * sigma));
      img.at<std::uint8_t>(y, x) = cv::saturate_cast<std::uint8_t>(v);
    }
  OrbExtractor orb;
  std::vector<cv::KeyPoint> k;
  cv::Mat d;
  orb.extract(img, k, d);
  const ScalePyramid& pyr = orb.pyramid();
  ASSERT_EQ(orb.levels().size(), 8u);
  double worst = 0, worst_plain = 0;
  for (int l = 1; l < pyr.levels(); ++l) {
    const cv::Mat& level = orb.levels()[static_cast<std::size_t>(l)];
    ASSERT_EQ(level.size(), pyr.level_size(img.size(), l));
    for (const auto& c : spots) {
      const cv::Point2f guess = pyr.to_level(cv::Point2f(static_cast<float>(c.x), static_cast<float>(c.y)), l, img.size());
      const double r = 2.5 * sigma * pyr.inv_scale[static_cast<std::size_t>(l)];
      double sw = 0, sx = 0, sy = 0;
      for (int y = static_cast<int>(guess.y - r); y <= static_cast<int>(guess.y + r) + 1; ++y)
        for (int x = static_cast<int>(guess.x - r); x <= static_cast<int>(guess.x + r) + 1; ++x) {
          if ((x - guess.x) * (x - guess.x) + (y - guess.y) * (y - guess.y) > r * r) continue;
          const double w = level.at<std::uint8_t>(y, x) - 20.0;
          sw += w;
          sx += w * x;
          sy += w * y;
        }
      const cv::Point2f centroid(static_cast<float>(sx / sw), static_cast<float>(sy / sw));
      const cv::Point2f back = pyr.to_image(centroid, l, img.size());
      worst = std::max(worst, std::hypot(back.x - c.x, back.y - c.y));
      const float s = pyr.scale[static_cast<std::size_t>(l)];
      worst_plain = std::max(worst_plain, std::hypot(centroid.x * s - c.x, centroid.y * s - c.y));
      const cv::Point2f there = pyr.to_level(back, l, img.size());
      EXPECT_NEAR(there.x, centroid.x, 1e-3);
      EXPECT_NEAR(there.y, centroid.y, 1e-3);
    }
  }
  EXPECT_LT(worst, 0.1) << "px, over levels 1-7";
  EXPECT_GT(worst_plain, 1.0) << "px: the test must tell the two rules apart";
}

TEST(OrbExtractor, ParallelLevelsGiveIdenticalOutput) {
  const cv::Mat img = test::textured_image(640, 480, 9);
  OrbExtractorOptions serial;
  serial.parallel_levels = false;
  OrbExtractorOptions parallel;
  parallel.parallel_levels = true;
  OrbExtractor a(serial), b(parallel);
  std::vector<cv::KeyPoint> ka, kb;
  cv::Mat da, db;
  a.extract(img, ka, da);
  b.extract(img, kb, db);
  ASSERT_EQ(ka.size(), kb.size());
  for (std::size_t i = 0; i < ka.size(); ++i) {
    EXPECT_EQ(ka[i].pt, kb[i].pt);
    EXPECT_EQ(ka[i].angle, kb[i].angle);
    EXPECT_EQ(ka[i].octave, kb[i].octave);
  }
  EXPECT_EQ(cv::norm(da, db, cv::NORM_HAMMING), 0.0);
}

TEST(OrbExtractor, BlankAndTinyImagesGiveNothing) {
  OrbExtractor orb;
  std::vector<cv::KeyPoint> k;
  cv::Mat d;
  orb.extract(cv::Mat(480, 640, CV_8UC1, cv::Scalar(90)), k, d);
  EXPECT_TRUE(k.empty());
  orb.extract(cv::Mat(10, 10, CV_8UC1, cv::Scalar(0)), k, d);
  EXPECT_TRUE(k.empty());
  orb.extract(cv::Mat(), k, d);
  EXPECT_TRUE(k.empty());
}

// A plain wall under sensor noise has no corner at all, so every keypoint found on it is
// noise. The noise-adaptive fallback threshold must leave (almost) none there, yet keep the
// real corners of a textured image under the same noise.
TEST(OrbExtractor, NoiseAdaptiveThresholdFindsNoCornersOnAPlainNoisyWall) {
  cv::Mat noise(480, 640, CV_32F);
  cv::RNG rng(5);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 2.5);  // the generated worlds' level (docs/slam.md)
  cv::Mat wall;
  cv::Mat(cv::Mat(480, 640, CV_32F, cv::Scalar(140)) + noise).convertTo(wall, CV_8U);
  OrbExtractorOptions fixed, threshold_only;
  fixed.noise_factor = 0;  // ORB-SLAM's fixed fallback of 7 grey levels
  fixed.denoise_above = 0;
  threshold_only.denoise_above = 0;  // the raised threshold alone (the smoothing: next test)
  OrbExtractor plain(fixed), adaptive(threshold_only);
  std::vector<cv::KeyPoint> k_fixed, k_adaptive;
  cv::Mat d;
  plain.extract(wall, k_fixed, d);
  adaptive.extract(wall, k_adaptive, d);
  std::printf("plain noisy wall: %zu keypoints at threshold 7, %zu at %d (sigma %.2f)\n", k_fixed.size(),
              k_adaptive.size(), adaptive.last_min_th_fast(), adaptive.last_noise_sigma());
  EXPECT_NEAR(adaptive.last_noise_sigma(), 2.5, 0.3);
  EXPECT_GT(k_fixed.size(), 50u);  // the failure mode: noise corners where nothing is
  EXPECT_LE(k_adaptive.size(), 2u);

  cv::Mat textured;
  cv::Mat tex32;
  test::textured_image(640, 480, 3).convertTo(tex32, CV_32F);
  cv::Mat(tex32 + noise).convertTo(textured, CV_8U);
  std::vector<cv::KeyPoint> k_tex;
  adaptive.extract(textured, k_tex, d);
  EXPECT_GT(k_tex.size(), 900u);  // the real corners pass the strong threshold as before
}

// Smoothing above a noise level (denoise_above): on low-contrast texture under the generated
// worlds' noise (sigma 2.5), more of the corners the noise-free image has are found with the
// smoothing than with the raised threshold alone, a plain noisy wall still gives no corners,
// and an image below the level is processed exactly as without the option.
TEST(OrbExtractor, DenoisingAboveANoiseLevelFindsTheFaintTexturesCorners) {
  cv::Mat tex32;
  test::textured_image(640, 480, 3).convertTo(tex32, CV_32F);
  const cv::Mat faint = 128.0 + 0.2 * (tex32 - 128.0);  // far, low-contrast texture
  auto noisy = [&](const cv::Mat& base, int seed, double sigma) {
    cv::Mat n(base.size(), CV_32F), out;
    cv::RNG rng(static_cast<std::uint64_t>(seed));
    rng.fill(n, cv::RNG::NORMAL, 0.0, sigma);
    cv::Mat(base + n).convertTo(out, CV_8U);
    return out;
  };
  OrbExtractorOptions no_smoothing, with_smoothing;
  no_smoothing.denoise_above = 0;
  with_smoothing.denoise_above = 1.5;
  OrbExtractor plain(no_smoothing), smoothing(with_smoothing);
  std::vector<cv::KeyPoint> truth;
  cv::Mat d;
  {
    cv::Mat clean;
    faint.convertTo(clean, CV_8U);
    OrbExtractor(OrbExtractorOptions{}).extract(clean, truth, d);
  }
  auto true_corners = [&](OrbExtractor& orb, const cv::Mat& img) {
    std::vector<cv::KeyPoint> k;
    cv::Mat desc;
    orb.extract(img, k, desc);
    std::size_t n = 0;
    for (const auto& t : truth)
      for (const auto& p : k)
        if (cv::norm(p.pt - t.pt) < 2.0 * std::pow(1.2, t.octave)) {
          ++n;
          break;
        }
    return n;
  };
  const cv::Mat img = noisy(faint, 1, 2.5);
  const std::size_t n_plain = true_corners(plain, img), n_smooth = true_corners(smoothing, img);
  EXPECT_FALSE(plain.last_denoised());
  EXPECT_TRUE(smoothing.last_denoised());
  std::printf("faint texture, noise 2.5: %zu of its %zu corners found at threshold %d, %zu with smoothing (threshold %d)\n",
              n_plain, truth.size(), plain.last_min_th_fast(), n_smooth, smoothing.last_min_th_fast());
  EXPECT_GT(n_smooth, n_plain + truth.size() / 20);

  std::vector<cv::KeyPoint> k;
  smoothing.extract(noisy(cv::Mat(480, 640, CV_32F, cv::Scalar(140)), 5, 2.5), k, d);
  EXPECT_LE(k.size(), 2u) << "noise corners on a plain wall";

  const cv::Mat quiet = noisy(tex32, 3, 0.5);  // 7-Scenes' level: below denoise_above
  std::vector<cv::KeyPoint> k1, k2;
  cv::Mat d1, d2;
  plain.extract(quiet, k1, d1);
  smoothing.extract(quiet, k2, d2);
  EXPECT_FALSE(smoothing.last_denoised());
  ASSERT_EQ(k1.size(), k2.size());
  EXPECT_EQ(cv::norm(d1, d2, cv::NORM_HAMMING), 0);
}

TEST(OrbExtractor, SpreadsBetterThanOpenCvOnRealImage) {
  const auto path = std::filesystem::path(BUILTSCENE_SOURCE_DIR) / "../shared/data/7scenes-kitchen/rgb";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "real data not found at " << path;
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(path)) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  ASSERT_FALSE(files.empty());
  double ours_sum = 0, cv_sum = 0;
  int n = 0;
  for (std::size_t i = 0; i < files.size(); i += files.size() / 5) {
    const cv::Mat gray = cv::imread(files[i].string(), cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(gray.empty());
    OrbExtractor orb;
    std::vector<cv::KeyPoint> k, c;
    cv::Mat d, e;
    orb.extract(gray, k, d);
    cv::ORB::create(1000)->detectAndCompute(gray, cv::noArray(), c, e);
    ours_sum += grid_coverage(k, gray.size(), 32, 24);
    cv_sum += grid_coverage(c, gray.size(), 32, 24);
    ++n;
  }
  std::printf("coverage of a 32x24 grid: ours %.3f, cv::ORB %.3f\n", ours_sum / n, cv_sum / n);
  EXPECT_GT(ours_sum, cv_sum);
}

}  // namespace
}  // namespace builtscene
