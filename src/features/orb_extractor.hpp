#pragma once
// ORB features (Rublee et al. 2011) as ORB-SLAM uses them: a scale pyramid, FAST corners
// with a per-cell adaptive threshold (ini_th_fast, falling back to min_th_fast in cells where
// nothing passes), an even spread per level by quadtree, orientation by intensity centroid,
// and 256-bit rotated BRIEF descriptors computed on the Gaussian-smoothed level.
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "features/feature_extractor.hpp"
#include "features/keypoint_distribution.hpp"

namespace builtscene {

class SettingsFile;

struct OrbExtractorOptions {
  int n_features = 1000;
  float scale_factor = 1.2f;
  int n_levels = 8;
  int ini_th_fast = 20;
  int min_th_fast = 7;
  // The fallback threshold is raised to noise_factor times the image's noise sigma
  // (core/image_noise.hpp) when that is higher, never above ini_th_fast; 0 turns it off.
  // Why: in a low-contrast cell, FAST at 7 grey levels fires on sensor noise once sigma is
  // above ~1.5; those corners have random descriptors, yet they take the cell's share of the
  // features and, with depth, become map points that match noise in the next frame. On the
  // generated corridor (sigma 2.5) they made a keyframe of every second frame and shrank the
  // trajectory by 10-16 % (docs/slam.md, "Image noise"). 6 sigma: 7scenes (sigma ~0.5)
  // keeps 7; generated worlds (sigma 2-2.5) get 12-15.
  double noise_factor = 6.0;
  // Above this much image noise (grey levels, estimated per frame as for noise_factor), the
  // second FAST pass (cells where nothing passed ini_th_fast) runs on the level smoothed by a
  // Gaussian of denoise_sigma_px, at noise_factor times the smoothed image's noise; strong
  // corners, orientation and descriptors still come from the unsmoothed level. 0 = never.
  // Why: at sigma ~2.5 the raised threshold (15) drops the faint corners of far texture and
  // plain walls, and the generated corridor's loop then bends. Off by default (docs/slam.md,
  // "Image noise, part 2"): at 1.5 it took the 2-loop corridor from 0.805 to 0.412 m and the
  // office from 12.3 to 10.7 cm, but the corridor's first 300 frames, threaded, made 162
  // keyframes instead of 27 (ATE 26.6 against 4.4 cm).
  double denoise_above = 0.0;
  double denoise_sigma_px = 1.0;
  // Process pyramid levels on OpenCV's thread pool (same output either way). Off by default:
  // on the shared 2-core machine it did not lower the median time (load 10, not conclusive),
  // and the local-mapping thread needs the second core.
  bool parallel_levels = false;

  // ORBextractor.nFeatures, .scaleFactor, .nLevels, .iniThFAST, .minThFAST, .noiseFactor,
  // .denoiseAbove, .denoiseSigma when present;
  // InputError naming the key for values out of range.
  static OrbExtractorOptions from_settings(const SettingsFile& settings);
  void validate() const;  // throws InputError
};

// Per-level scale factors and the measurement variances derived from them.
struct ScalePyramid {
  float scale_factor = 1.2f;
  std::vector<float> scale;          // scale[l] = scale_factor^l
  std::vector<float> inv_scale;
  std::vector<float> sigma2;         // scale^2: pixel noise variance at that level
  std::vector<float> inv_sigma2;
  static ScalePyramid make(float scale_factor, int n_levels);
  int levels() const { return static_cast<int>(scale.size()); }

  // Size of level l of an image of size `image`, as OrbExtractor builds it.
  cv::Size level_size(cv::Size image, int l) const;
  // Pixel coordinates between level l and the image it was made from (level 0). Each level is
  // resized from the one before (cv::resize keeps pixel centres in place), so per axis
  // x0 + 0.5 = (xl + 0.5) * W0 / Wl with the level's rounded size Wl. Multiplying by scale[l],
  // as ORB-SLAM does, puts a level-7 keypoint of a 640 x 480 image up to 1.3 px up and to the
  // left of where it was found (docs/slam.md, "Keypoint coordinates on coarse levels").
  cv::Point2f to_image(cv::Point2f at_level, int l, cv::Size image) const;
  cv::Point2f to_level(cv::Point2f in_image, int l, cv::Size image) const;
};

class OrbExtractor : public FeatureExtractor {
 public:
  explicit OrbExtractor(OrbExtractorOptions options = {});

  // Grayscale 8-bit image in; keypoints in level-0 pixel coordinates (octave = level,
  // angle in degrees, size = patch diameter at that level) and one 32-byte descriptor row
  // per keypoint. An image too small for the pyramid gives no keypoints.
  void extract(const cv::Mat& gray, std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors) override;

  // Orientation and descriptor at given keypoints instead of detected ones (for positions
  // mapped from another image by a known homography): `pt` in level-0 pixels, `octave` the
  // level. Sets angle and size; rows follow the input order. Builds the pyramid of `gray`
  // like extract(). Every keypoint must lie at least border() pixels inside its level
  // (std::out_of_range otherwise).
  void describe(const cv::Mat& gray, std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors);
  // Smallest distance, in pixels of its level, between a described keypoint and the border.
  static int border();

  const OrbExtractorOptions& options() const { return options_; }
  const ScalePyramid& pyramid() const override { return pyramid_; }
  DescriptorMetric metric() const override { return DescriptorMetric::orb(); }
  // The image pyramid of the last extract() call (level 0 = the input).
  const std::vector<cv::Mat>& levels() const { return levels_; }
  // The last extract() call's noise estimate (grey levels) and the fallback FAST threshold
  // it led to.
  double last_noise_sigma() const { return noise_sigma_; }
  int last_min_th_fast() const { return min_th_fast_now_; }
  bool last_denoised() const { return denoised_; }  // OrbExtractorOptions::denoise_above

 private:
  OrbExtractorOptions options_;
  ScalePyramid pyramid_;
  std::vector<int> features_per_level_;
  std::vector<int> umax_;  // half-width of the circular patch per row offset
  std::vector<cv::Mat> levels_;
  std::vector<std::vector<cv::KeyPoint>> per_level_;
  double noise_sigma_ = 0;
  int min_th_fast_now_ = 0;
  bool denoised_ = false;
  cv::Mat smoothed_;  // level 0 smoothed, for its noise estimate
  // The noise estimate, the optional smoothing and the pyramid of one input image.
  void prepare(const cv::Mat& gray);
  // Working memory of one pyramid level, kept across frames: at 30 frames per second,
  // allocating these per frame (about 1 MB of smoothed images alone) cost page faults and
  // malloc time worth ~10 % of the extraction.
  struct LevelScratch {
    std::vector<cv::KeyPoint> candidates, weak, kept;
    std::vector<char> has_strong;
    QuadtreeScratch quadtree;
    cv::Mat blurred, descriptors, smoothed;
    std::vector<std::uint16_t> smoothing;
  };
  std::vector<LevelScratch> scratch_;

  void build_pyramid(const cv::Mat& gray);
  // Detected, spread keypoints of `level` into `out` (level pixels).
  void detect_level(int level, std::vector<cv::KeyPoint>& out);
  void describe_level(int level, std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors);
  float orientation(const cv::Mat& image, cv::Point2f pt) const;
};

}  // namespace builtscene
