#pragma once
// Barcode region detection (source section 4.3.2): binarize (a global threshold, or edges where
// backgrounds vary), dilate, contours with hierarchy; keep contours with at least N children
// (the bars are holes in a bright label), whose polygon approximation has at most M vertices and
// whose area is at least A.
#include <vector>

#include <opencv2/core.hpp>

namespace builtscene::barcode {

// threshold: global, T x full scale (the source's choice for uniform backgrounds);
// adaptive: brighter than the local mean by an offset (labels in shadow and in light alike);
// edges: Canny edges, for backgrounds that vary.
enum class Binarization { threshold, adaptive, edges };

struct RegionOptions {
  Binarization mode = Binarization::threshold;
  double threshold = 0.45;    // fraction of full scale (0..1), as in the source's Figure 4.12
  int min_children = 6;       // N
  int max_vertices = 8;       // M, after approxPolyDP at 3 % of the perimeter
  double min_area = 1500.0;   // A, in full-resolution pixels
  double min_aspect = 1.3;    // long / short side of the minimum-area box: 1D labels are elongated
  double max_aspect = 12.0;
  int adaptive_block = 41;    // local-mean window (pixels of the downscaled image)
  double adaptive_offset = 12;  // gray levels above the local mean
  int dilate_px = 1;          // dilation of the foreground (edges mode: closes bar edges)
  double scale = 0.5;         // detection runs on a downscaled copy for speed; 1 = full size
  double pad = 0.12;          // boxes grow by this fraction of their size on each side
};

// A candidate region: a rotated box in full-resolution frame coordinates.
struct Region {
  cv::RotatedRect box;
  int children = 0;
  double area = 0;
  cv::Rect bounds(const cv::Size& frame) const;  // padded axis-aligned bounds clipped to the frame
};

class RegionDetector {
 public:
  explicit RegionDetector(RegionOptions options = {}) : options_(options) {}
  // Regions sorted by position (top to bottom, left to right): deterministic order.
  std::vector<Region> detect(const cv::Mat& frame) const;
  const RegionOptions& options() const { return options_; }

 private:
  RegionOptions options_;
};

}  // namespace builtscene::barcode
