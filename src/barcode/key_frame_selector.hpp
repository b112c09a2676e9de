#pragma once
// Key-frame selection by gray-histogram differences (source section 4.3.3, Figure 4.8):
// 1. gray histogram of every frame and the difference between adjacent frames;
// 2. differences above a shot threshold split the video into virtual shots;
// 3. in each shot, frames whose difference exceeds k times the shot's mean difference;
// 4. the frame just before each of those is a key frame.
#include <cstddef>
#include <vector>

#include <opencv2/core.hpp>

namespace builtscene::barcode {

struct KeyFrameOptions {
  double k = 0.7;                // the source's best setting (Figure 4.14)
  double shot_threshold = -1.0;  // < 0: automatic, from the differences themselves
};

class KeyFrameSelector {
 public:
  static constexpr int kBins = 64;

  // Normalized gray histogram (sums to 1) of a frame, from every `step`-th pixel in both directions.
  static std::vector<float> histogram(const cv::Mat& frame, int step = 4);
  // L1 distance between two normalized histograms, in [0, 2].
  static double difference(const std::vector<float>& a, const std::vector<float>& b);

  // Automatic shot threshold: median + 8 * MAD of the differences (robust to the few large
  // ones that split shots), and at least 3 times the median.
  static double auto_shot_threshold(const std::vector<double>& diffs);

  // diffs[i] = difference between frame i and frame i-1 (diffs[0] = 0). Returns sorted frame
  // indices of the key frames.
  static std::vector<std::size_t> select(const std::vector<double>& diffs, const KeyFrameOptions& options);
};

}  // namespace builtscene::barcode
