#include "features/orb_extractor.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "core/errors.hpp"
#include "core/image_noise.hpp"
#include "core/settings_file.hpp"
#include "features/brief_smoothing.hpp"
#include "features/keypoint_distribution.hpp"
#include "features/orb_pattern.hpp"

namespace builtscene {
namespace {

// Keypoints stay this far from the level's border: the orientation disk and the BRIEF
// pattern both have radius 15, FAST needs 3 more pixels.
constexpr int kBorder = kOrbPatchRadius + 1;
// Cell size (pixels of the level) of the adaptive FAST threshold.
constexpr int kThresholdCell = 32;

}  // namespace

OrbExtractorOptions OrbExtractorOptions::from_settings(const SettingsFile& s) {
  OrbExtractorOptions o;
  o.n_features = s.get_int("ORBextractor.nFeatures", o.n_features);
  o.scale_factor = static_cast<float>(s.get_double("ORBextractor.scaleFactor", o.scale_factor));
  o.n_levels = s.get_int("ORBextractor.nLevels", o.n_levels);
  o.ini_th_fast = s.get_int("ORBextractor.iniThFAST", o.ini_th_fast);
  o.min_th_fast = s.get_int("ORBextractor.minThFAST", o.min_th_fast);
  o.noise_factor = s.get_double("ORBextractor.noiseFactor", o.noise_factor);
  o.denoise_above = s.get_double("ORBextractor.denoiseAbove", o.denoise_above);
  o.denoise_sigma_px = s.get_double("ORBextractor.denoiseSigma", o.denoise_sigma_px);
  try {
    o.validate();
  } catch (const InputError& e) {
    throw InputError(located(s.path(), 0, e.what()));
  }
  return o;
}

void OrbExtractorOptions::validate() const {
  if (n_features < 1 || n_features > 100000) throw InputError("ORBextractor.nFeatures must be in [1, 100000]");
  if (!(scale_factor > 1.0f && scale_factor < 4.0f)) throw InputError("ORBextractor.scaleFactor must be in (1, 4)");
  if (n_levels < 1 || n_levels > 20) throw InputError("ORBextractor.nLevels must be in [1, 20]");
  if (ini_th_fast < 1 || ini_th_fast > 255) throw InputError("ORBextractor.iniThFAST must be in [1, 255]");
  if (min_th_fast < 1 || min_th_fast > ini_th_fast) throw InputError("ORBextractor.minThFAST must be in [1, iniThFAST]");
  if (!(noise_factor >= 0 && noise_factor <= 100)) throw InputError("ORBextractor.noiseFactor must be in [0, 100]");
  if (!(denoise_above >= 0 && denoise_above <= 255)) throw InputError("ORBextractor.denoiseAbove must be in [0, 255] (0 = off)");
  if (!(denoise_sigma_px >= 0.3 && denoise_sigma_px <= 5)) throw InputError("ORBextractor.denoiseSigma must be in [0.3, 5] pixels");
}

ScalePyramid ScalePyramid::make(float scale_factor, int n_levels) {
  ScalePyramid p;
  p.scale_factor = scale_factor;
  float s = 1.0f;
  for (int l = 0; l < n_levels; ++l) {
    p.scale.push_back(s);
    p.inv_scale.push_back(1.0f / s);
    p.sigma2.push_back(s * s);
    p.inv_sigma2.push_back(1.0f / (s * s));
    s *= scale_factor;
  }
  return p;
}

cv::Size ScalePyramid::level_size(cv::Size image, int l) const {
  const float inv = inv_scale[static_cast<std::size_t>(l)];
  return {static_cast<int>(std::lround(image.width * inv)), static_cast<int>(std::lround(image.height * inv))};
}

cv::Point2f ScalePyramid::to_image(cv::Point2f at_level, int l, cv::Size image) const {
  const cv::Size s = level_size(image, l);
  return {static_cast<float>((at_level.x + 0.5) * image.width / s.width - 0.5),
          static_cast<float>((at_level.y + 0.5) * image.height / s.height - 0.5)};
}

cv::Point2f ScalePyramid::to_level(cv::Point2f in_image, int l, cv::Size image) const {
  const cv::Size s = level_size(image, l);
  return {static_cast<float>((in_image.x + 0.5) * s.width / image.width - 0.5),
          static_cast<float>((in_image.y + 0.5) * s.height / image.height - 0.5)};
}

OrbExtractor::OrbExtractor(OrbExtractorOptions options) : options_(options) {
  options_.validate();
  pyramid_ = ScalePyramid::make(options_.scale_factor, options_.n_levels);
  // Features per level proportional to the level's linear size (a geometric series in
  // 1/scale_factor), the last level taking the remainder.
  const double f = 1.0 / options_.scale_factor;
  const int L = options_.n_levels;
  double per = options_.n_features * (1.0 - f) / (1.0 - std::pow(f, L));
  if (L == 1) per = options_.n_features;
  int total = 0;
  for (int l = 0; l < L - 1; ++l) {
    const int n = static_cast<int>(std::lround(per));
    features_per_level_.push_back(n);
    total += n;
    per *= f;
  }
  features_per_level_.push_back(std::max(0, options_.n_features - total));
  scratch_.resize(static_cast<std::size_t>(L));
  per_level_.resize(static_cast<std::size_t>(L));

  // Circular patch: for each row offset v, the largest u with u^2 + v^2 <= r^2.
  umax_.resize(kOrbPatchRadius + 1);
  for (int v = 0; v <= kOrbPatchRadius; ++v)
    umax_[static_cast<std::size_t>(v)] =
        static_cast<int>(std::floor(std::sqrt(static_cast<double>(kOrbPatchRadius * kOrbPatchRadius - v * v)) + 1e-9));
}

void OrbExtractor::build_pyramid(const cv::Mat& gray) {
  levels_.resize(static_cast<std::size_t>(options_.n_levels));
  levels_[0] = gray;
  for (int l = 1; l < options_.n_levels; ++l) {
    const cv::Size sz = pyramid_.level_size(gray.size(), l);
    if (sz.width <= 2 * kBorder || sz.height <= 2 * kBorder) {
      levels_[static_cast<std::size_t>(l)] = cv::Mat();
      continue;
    }
    cv::resize(levels_[static_cast<std::size_t>(l - 1)], levels_[static_cast<std::size_t>(l)], sz, 0, 0, cv::INTER_LINEAR);
  }
}

void OrbExtractor::detect_level(int level, std::vector<cv::KeyPoint>& out) {
  out.clear();
  const cv::Mat& img = levels_[static_cast<std::size_t>(level)];
  if (img.empty() || img.cols <= 2 * kBorder || img.rows <= 2 * kBorder) return;
  LevelScratch& scratch = scratch_[static_cast<std::size_t>(level)];
  // FAST at ini_th_fast over the inner region; then, only in cells where nothing passed,
  // FAST again at min_th_fast on that cell (plus the 3-pixel ring FAST needs). The second
  // pass touches only low-contrast cells, which keeps the cost near one FAST pass.
  const int x0 = kBorder - 3, y0 = kBorder - 3;
  const cv::Rect inner(x0, y0, img.cols - 2 * x0, img.rows - 2 * y0);
  std::vector<cv::KeyPoint>& strong_kps = scratch.candidates;
  cv::FAST(img(inner), strong_kps, options_.ini_th_fast, true, cv::FastFeatureDetector::TYPE_9_16);
  const int cells_x = std::max(1, (img.cols - 2 * kBorder) / kThresholdCell);
  const int cells_y = std::max(1, (img.rows - 2 * kBorder) / kThresholdCell);
  const float cw = static_cast<float>(img.cols - 2 * kBorder) / static_cast<float>(cells_x);
  const float ch = static_cast<float>(img.rows - 2 * kBorder) / static_cast<float>(cells_y);
  auto inside = [&](const cv::KeyPoint& k) {
    return k.pt.x >= kBorder && k.pt.y >= kBorder && k.pt.x < static_cast<float>(img.cols - kBorder) &&
           k.pt.y < static_cast<float>(img.rows - kBorder);
  };
  std::vector<char>& has_strong = scratch.has_strong;
  has_strong.assign(static_cast<std::size_t>(cells_x * cells_y), 0);
  std::vector<cv::KeyPoint>& kept = scratch.kept;
  kept.clear();
  for (auto& k : strong_kps) {
    k.pt.x += static_cast<float>(x0);
    k.pt.y += static_cast<float>(y0);
    if (!inside(k)) continue;
    const int cx = std::min(cells_x - 1, static_cast<int>((k.pt.x - kBorder) / cw));
    const int cy = std::min(cells_y - 1, static_cast<int>((k.pt.y - kBorder) / ch));
    has_strong[static_cast<std::size_t>(cy * cells_x + cx)] = 1;
    kept.push_back(k);
  }
  if (min_th_fast_now_ < options_.ini_th_fast) {
    const cv::Mat* weak_img = &img;
    if (denoised_) {
      if (level == 0) scratch.smoothed = smoothed_;
      else cv::GaussianBlur(img, scratch.smoothed, cv::Size(), options_.denoise_sigma_px);
      weak_img = &scratch.smoothed;
    }
    // Adjacent weak cells of a row are scanned in one call: a FAST call has a fixed cost
    // (threshold table, row buffers) that dominated when every 32-pixel cell paid it.
    std::vector<cv::KeyPoint>& weak = scratch.weak;
    auto cell_x = [&](int cx) {
      return cx == cells_x ? img.cols - kBorder : kBorder + static_cast<int>(std::floor(static_cast<float>(cx) * cw));
    };
    for (int cy = 0; cy < cells_y; ++cy) {
      const int cell_y0 = kBorder + static_cast<int>(std::floor(static_cast<float>(cy) * ch));
      const int cell_y1 = cy == cells_y - 1 ? img.rows - kBorder : kBorder + static_cast<int>(std::floor(static_cast<float>(cy + 1) * ch));
      for (int cx = 0; cx < cells_x;) {
        if (has_strong[static_cast<std::size_t>(cy * cells_x + cx)]) {
          ++cx;
          continue;
        }
        int run_end = cx + 1;
        while (run_end < cells_x && !has_strong[static_cast<std::size_t>(cy * cells_x + run_end)]) ++run_end;
        const int x0r = cell_x(cx), x1r = cell_x(run_end);
        cx = run_end;
        const cv::Rect roi(x0r - 3, cell_y0 - 3, x1r - x0r + 6, cell_y1 - cell_y0 + 6);
        weak.clear();
        cv::FAST((*weak_img)(roi), weak, min_th_fast_now_, true, cv::FastFeatureDetector::TYPE_9_16);
        for (auto& k : weak) {
          k.pt.x += static_cast<float>(roi.x);
          k.pt.y += static_cast<float>(roi.y);
          // Only the run's cells: the ring belongs to the neighbours.
          if (k.pt.x < x0r || k.pt.y < cell_y0 || k.pt.x >= x1r || k.pt.y >= cell_y1) continue;
          kept.push_back(k);
        }
      }
    }
  }
  const cv::Rect2f bounds(static_cast<float>(kBorder), static_cast<float>(kBorder),
                          static_cast<float>(img.cols - 2 * kBorder), static_cast<float>(img.rows - 2 * kBorder));
  distribute_quadtree(kept, bounds, features_per_level_[static_cast<std::size_t>(level)], out, scratch.quadtree);
}

float OrbExtractor::orientation(const cv::Mat& image, cv::Point2f pt) const {
  const int x0 = cvRound(pt.x), y0 = cvRound(pt.y);
  const std::uint8_t* center = image.ptr<std::uint8_t>(y0) + x0;
  const int step = static_cast<int>(image.step1());
  int m01 = 0, m10 = 0;
  for (int u = -kOrbPatchRadius; u <= kOrbPatchRadius; ++u) m10 += u * center[u];
  for (int v = 1; v <= kOrbPatchRadius; ++v) {
    int v_sum = 0;
    const int d = umax_[static_cast<std::size_t>(v)];
    for (int u = -d; u <= d; ++u) {
      const int below = center[u + v * step], above = center[u - v * step];
      v_sum += below - above;
      m10 += u * (below + above);
    }
    m01 += v * v_sum;
  }
  return cv::fastAtan2(static_cast<float>(m01), static_cast<float>(m10));
}

void OrbExtractor::describe_level(int l, std::vector<cv::KeyPoint>& kps, cv::Mat& desc) {
  desc.create(static_cast<int>(kps.size()), 32, CV_8UC1);
  if (kps.empty()) return;
  const cv::Mat& img = levels_[static_cast<std::size_t>(l)];
  LevelScratch& scratch = scratch_[static_cast<std::size_t>(l)];
  cv::Mat& blurred = scratch.blurred;
  smooth_for_brief(img, blurred, scratch.smoothing);
  const auto& table = rotated_pattern_table();
  const float scale = pyramid_.scale[static_cast<std::size_t>(l)];
  const int step = static_cast<int>(blurred.step1());
  int row = 0;
  for (auto& k : kps) {
    k.angle = orientation(img, k.pt);
    const std::uint8_t* center = blurred.ptr<std::uint8_t>(cvRound(k.pt.y)) + cvRound(k.pt.x);
    const BriefPair* pairs = table.pairs(k.angle);
    std::uint8_t* d = desc.ptr<std::uint8_t>(row++);
    for (int b = 0; b < 32; ++b, pairs += 8) {
      std::uint8_t byte = 0;
      for (int bit = 0; bit < 8; ++bit) {
        const BriefPair& p = pairs[bit];
        byte |= static_cast<std::uint8_t>((center[p.y1 * step + p.x1] < center[p.y2 * step + p.x2]) << bit);
      }
      d[b] = byte;
    }
    k.octave = l;
    k.size = 2.0f * kOrbPatchRadius * scale;
    k.pt = pyramid_.to_image(k.pt, l, levels_[0].size());
  }
}

void OrbExtractor::prepare(const cv::Mat& gray) {
  noise_sigma_ = 0;
  min_th_fast_now_ = options_.min_th_fast;
  if (options_.noise_factor > 0 || options_.denoise_above > 0)
    noise_sigma_ = estimate_image_noise_sigma(gray, 4);  // 19k samples of 640 x 480: enough for a median
  denoised_ = options_.denoise_above > 0 && noise_sigma_ > options_.denoise_above;
  if (denoised_) cv::GaussianBlur(gray, smoothed_, cv::Size(), options_.denoise_sigma_px);
  build_pyramid(gray);
  if (options_.noise_factor > 0) {
    const double sigma = denoised_ ? estimate_image_noise_sigma(smoothed_, 4) : noise_sigma_;
    const int from_noise = static_cast<int>(std::ceil(options_.noise_factor * sigma));
    min_th_fast_now_ = std::clamp(from_noise, options_.min_th_fast, options_.ini_th_fast);
  }
}

void OrbExtractor::extract(const cv::Mat& gray_in, std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors) {
  keypoints.clear();
  descriptors.release();
  if (gray_in.empty()) return;
  CV_Assert(gray_in.type() == CV_8UC1);
  prepare(gray_in);
  // Levels are independent once the pyramid exists: detection, orientation and description
  // run per level, in parallel when allowed; the result does not depend on the thread count.
  const auto L = static_cast<std::size_t>(options_.n_levels);
  auto& per_level = per_level_;
  auto work = [&](const cv::Range& r) {
    for (int l = r.start; l < r.end; ++l) {
      detect_level(l, per_level[static_cast<std::size_t>(l)]);
      describe_level(l, per_level[static_cast<std::size_t>(l)], scratch_[static_cast<std::size_t>(l)].descriptors);
    }
  };
  if (options_.parallel_levels) cv::parallel_for_(cv::Range(0, options_.n_levels), work);
  else work(cv::Range(0, options_.n_levels));

  std::size_t total = 0;
  for (const auto& v : per_level) total += v.size();
  keypoints.reserve(total);
  descriptors.create(static_cast<int>(total), 32, CV_8UC1);
  int row = 0;
  for (std::size_t l = 0; l < L; ++l) {
    if (per_level[l].empty()) continue;
    const cv::Mat& d = scratch_[l].descriptors;
    d.copyTo(descriptors.rowRange(row, row + d.rows));
    row += d.rows;
    keypoints.insert(keypoints.end(), per_level[l].begin(), per_level[l].end());
  }
}

int OrbExtractor::border() { return kBorder; }

void OrbExtractor::describe(const cv::Mat& gray, std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors) {
  descriptors.create(static_cast<int>(keypoints.size()), 32, CV_8UC1);
  if (keypoints.empty()) return;
  CV_Assert(gray.type() == CV_8UC1);
  prepare(gray);  // the same smoothing as extract() would apply
  const auto L = static_cast<std::size_t>(options_.n_levels);
  std::vector<std::vector<cv::KeyPoint>> per_level(L);
  std::vector<std::vector<std::size_t>> index(L);
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const cv::KeyPoint& k = keypoints[i];
    if (k.octave < 0 || k.octave >= options_.n_levels) throw std::out_of_range("OrbExtractor::describe: octave out of range");
    const auto l = static_cast<std::size_t>(k.octave);
    const cv::Mat& img = levels_[l];
    cv::KeyPoint at_level = k;
    at_level.pt = pyramid_.to_level(k.pt, k.octave, levels_[0].size());
    // Rounded like describe_level does, so the check covers the pixels it will read.
    const int x = cvRound(at_level.pt.x), y = cvRound(at_level.pt.y);
    if (img.empty() || x < kBorder || y < kBorder || x >= img.cols - kBorder || y >= img.rows - kBorder)
      throw std::out_of_range("OrbExtractor::describe: keypoint too close to the border of its level");
    per_level[l].push_back(at_level);
    index[l].push_back(i);
  }
  for (std::size_t l = 0; l < L; ++l) {
    if (per_level[l].empty()) continue;
    cv::Mat d;
    describe_level(static_cast<int>(l), per_level[l], d);
    for (std::size_t j = 0; j < index[l].size(); ++j) {
      keypoints[index[l][j]] = per_level[l][j];
      d.row(static_cast<int>(j)).copyTo(descriptors.row(static_cast<int>(index[l][j])));
    }
  }
}

}  // namespace builtscene
