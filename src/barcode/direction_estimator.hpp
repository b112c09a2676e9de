#pragma once
// Barcode direction from the corners at the bar ends (source section 4.3.1): Harris corners,
// a Hough transform of the corner points, the strongest peaks, a histogram of their angles;
// the fullest bin gives the normal of the lines through the bar ends, i.e. the bars' direction.
#include <optional>

#include <opencv2/core.hpp>

namespace builtscene::barcode {

struct DirectionOptions {
  int max_peaks = 20;          // Hough peaks kept
  int angle_bins = 10;         // histogram bins over the peak angles (0..180 degrees)
  double harris_quality = 0.02;  // corners above this fraction of the strongest response
  int max_corners = 1500;
  // Regions are shrunk to this longest side first. On every 10th frame of the generated
  // 2000-frame scan, 160 px let the pipeline read at least as many labels as 320 did, with the
  // estimate costing about 55 % as much (docs/barcodes.md).
  int max_side = 160;
};

// The bars' direction of one barcode in a region.
class DirectionEstimator {
 public:
  explicit DirectionEstimator(DirectionOptions options = {}) : options_(options) {}

  // Angle in degrees, [0, 180), of the scan direction (the line across all bars, along which a
  // decoder reads) in image coordinates: x right, y down, angle measured from +x towards +y.
  // An upright barcode gives ~0. Empty when there are too few corners.
  std::optional<double> scan_angle(const cv::Mat& gray) const;

  // The region turned so that its scan direction is horizontal (bars vertical), on a white
  // border large enough to hold the whole rotated region.
  static cv::Mat upright(const cv::Mat& gray, double scan_angle_deg);

 private:
  DirectionOptions options_;
};

}  // namespace builtscene::barcode
