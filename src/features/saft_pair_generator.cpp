#include "features/saft_pair_generator.hpp"

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "core/errors.hpp"
#include "features/keypoint_warp.hpp"
#include "features/saft_patch.hpp"

namespace builtscene {

cv::Mat linear_motion_blur(const cv::Mat& image, double length_px, double angle_rad) {
  if (!(length_px > 1.0)) return image.clone();
  // The kernel is the segment, splatted bilinearly from dense samples so that sub-pixel
  // lengths and any angle give a kernel whose mean is the centre and whose spread is the
  // segment's (length^2 / 12 along it).
  const int half = static_cast<int>(std::ceil(length_px / 2.0)) + 1;
  cv::Mat kernel = cv::Mat::zeros(2 * half + 1, 2 * half + 1, CV_32F);
  const int samples = static_cast<int>(std::ceil(length_px * 8.0));
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  for (int k = 0; k < samples; ++k) {
    const double t = ((k + 0.5) / samples - 0.5) * length_px;
    const double x = half + t * c, y = half + t * s;
    const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
    const double fx = x - x0, fy = y - y0;
    kernel.at<float>(y0, x0) += static_cast<float>((1 - fx) * (1 - fy));
    kernel.at<float>(y0, x0 + 1) += static_cast<float>(fx * (1 - fy));
    kernel.at<float>(y0 + 1, x0) += static_cast<float>((1 - fx) * fy);
    kernel.at<float>(y0 + 1, x0 + 1) += static_cast<float>(fx * fy);
  }
  kernel /= cv::sum(kernel)[0];
  // filter2D correlates; the flipped kernel makes it a convolution (the segment is symmetric
  // about its centre, so this only matters for rounding).
  cv::Mat flipped, out;
  cv::flip(kernel, flipped, -1);
  cv::filter2D(image, out, -1, flipped, cv::Point(-1, -1), 0.0, cv::BORDER_REFLECT_101);
  return out;
}

WarpedImage random_warp(const cv::Mat& gray, const SaftPairGeneratorOptions& o, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double w = gray.cols, hgt = gray.rows;
  const double s = std::exp(o.max_log_scale * u(rng));
  const double a = o.max_rotation_deg * CV_PI / 180.0 * u(rng);
  // Similarity about the centre, then a perspective push of the four corners.
  const cv::Matx33d to_centre(1, 0, -w / 2, 0, 1, -hgt / 2, 0, 0, 1);
  const cv::Matx33d back(1, 0, w / 2, 0, 1, hgt / 2, 0, 0, 1);
  const cv::Matx33d sim(s * std::cos(a), -s * std::sin(a), 0, s * std::sin(a), s * std::cos(a), 0, 0, 0, 1);
  const cv::Matx33d similarity = back * sim * to_centre;
  std::vector<cv::Point2f> src{{0, 0}, {float(w), 0}, {float(w), float(hgt)}, {0, float(hgt)}}, dst;
  for (const auto& c : src) {
    const cv::Vec3d q = similarity * cv::Vec3d(c.x, c.y, 1);
    dst.emplace_back(float(q[0] + o.max_perspective * w * u(rng)), float(q[1] + o.max_perspective * hgt * u(rng)));
  }
  WarpedImage out;
  out.h = cv::Matx33d(cv::getPerspectiveTransform(src, dst));
  cv::warpPerspective(gray, out.image, out.h, gray.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT_101);

  // Photometric changes: contrast and brightness, then blur (half the time: linear motion
  // or defocus), then noise.
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  cv::Mat f;
  out.image.convertTo(f, CV_32F, 0.6 + 0.8 * unit(rng), 40.0 * u(rng));
  if (unit(rng) < 0.5) {
    if (unit(rng) < o.motion_blur_share) {
      const double length = 2.0 + (o.max_motion_blur_px - 2.0) * unit(rng);
      f = linear_motion_blur(f, length, CV_PI * unit(rng));
    } else {
      const double sigma = 0.4 + 1.4 * unit(rng);
      cv::GaussianBlur(f, f, cv::Size(0, 0), sigma);
    }
  }
  cv::Mat noise(f.size(), CV_32F);
  cv::RNG cvrng(static_cast<std::uint64_t>(rng()));
  cvrng.fill(noise, cv::RNG::NORMAL, 0.0, 6.0 * unit(rng));
  f += noise;
  f.convertTo(out.image, CV_8U);  // saturates to 0..255
  return out;
}

SaftPairPool generate_saft_pairs(const std::vector<cv::Mat>& images, const SaftPairGeneratorOptions& o) {
  if (o.warps_per_image < 1 || o.keypoints_per_image < 1) throw InputError("SAFT pairs: warps and keypoints per image must be positive");
  std::mt19937_64 rng(o.seed);
  OrbExtractorOptions eo;
  eo.n_features = o.keypoints_per_image;
  OrbExtractor orb(eo), orb2(eo);
  SaftPairPool pool;
  std::vector<cv::Mat> firsts, seconds;
  for (std::size_t img = 0; img < images.size(); ++img) {
    const cv::Mat& gray = images[img];
    std::vector<cv::KeyPoint> kps;
    cv::Mat desc;
    orb.extract(gray, kps, desc);
    if (kps.empty()) continue;
    const cv::Mat patches1 = sample_saft_patches(orb.levels(), orb.pyramid(), kps);
    for (int wi = 0; wi < o.warps_per_image; ++wi) {
      const WarpedImage warped = random_warp(gray, o, rng);
      std::vector<cv::KeyPoint> mapped;
      std::vector<int> index;
      for (std::size_t k = 0; k < kps.size(); ++k) {
        auto m = warp_keypoint(warped.h, kps[k], orb.pyramid(), gray.size(), OrbExtractor::border() + 1);
        if (!m) continue;
        mapped.push_back(*m);
        index.push_back(static_cast<int>(k));
      }
      if (mapped.empty()) continue;
      cv::Mat d2;
      orb2.describe(warped.image, mapped, d2);  // sets the orientation seen in the warped image
      const cv::Mat patches2 = sample_saft_patches(orb2.levels(), orb2.pyramid(), mapped);
      for (std::size_t j = 0; j < mapped.size(); ++j) {
        firsts.push_back(patches1.row(index[j]));
        seconds.push_back(patches2.row(static_cast<int>(j)));
        pool.source.push_back(static_cast<int>(img));
        pool.position.push_back(kps[static_cast<std::size_t>(index[j])].pt);
      }
    }
  }
  if (!firsts.empty()) {
    cv::vconcat(firsts, pool.first);
    cv::vconcat(seconds, pool.second);
  }
  return pool;
}

int draw_non_matching(const SaftPairPool& pool, int i, std::mt19937_64& rng, float min_distance) {
  std::uniform_int_distribution<int> pick(0, pool.size() - 1);
  const auto ui = static_cast<std::size_t>(i);
  for (int attempt = 0; attempt < 100; ++attempt) {
    const int j = pick(rng);
    const auto uj = static_cast<std::size_t>(j);
    if (pool.source[uj] != pool.source[ui]) return j;
    const cv::Point2f d = pool.position[uj] - pool.position[ui];
    if (d.dot(d) >= min_distance * min_distance) return j;
  }
  throw Failure("SAFT pairs: no non-matching partner found (too few keypoints in the training images)");
}

}  // namespace builtscene
