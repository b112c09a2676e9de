#include "barcode/key_frame_selector.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace builtscene::barcode {

std::vector<float> KeyFrameSelector::histogram(const cv::Mat& frame, int step) {
  step = std::max(1, step);
  std::vector<float> h(kBins, 0.0f);
  if (frame.empty()) return h;
  std::size_t n = 0;
  const int ch = frame.channels();
  for (int y = 0; y < frame.rows; y += step) {
    const uchar* row = frame.ptr<uchar>(y);
    for (int x = 0; x < frame.cols; x += step) {
      int g;
      if (ch >= 3) {
        const uchar* p = row + static_cast<std::ptrdiff_t>(x) * ch;  // BGR
        g = (29 * p[0] + 150 * p[1] + 77 * p[2]) >> 8;
      } else {
        g = row[x];
      }
      ++h[static_cast<std::size_t>(g * kBins / 256)];
      ++n;
    }
  }
  for (auto& v : h) v /= static_cast<float>(std::max<std::size_t>(1, n));
  return h;
}

double KeyFrameSelector::difference(const std::vector<float>& a, const std::vector<float>& b) {
  double d = 0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) d += std::abs(static_cast<double>(a[i]) - b[i]);
  return d;
}

double KeyFrameSelector::auto_shot_threshold(const std::vector<double>& diffs) {
  if (diffs.size() < 3) return 2.0;
  std::vector<double> v(diffs.begin() + 1, diffs.end());
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  const double median = v[v.size() / 2];
  for (auto& x : v) x = std::abs(x - median);
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  const double mad = v[v.size() / 2];
  return std::max(median + 8.0 * mad, 3.0 * median) + 1e-9;
}

std::vector<std::size_t> KeyFrameSelector::select(const std::vector<double>& diffs, const KeyFrameOptions& options) {
  std::vector<std::size_t> keys;
  if (diffs.empty()) return keys;
  if (diffs.size() == 1) return {0};
  const double shot_thr = options.shot_threshold >= 0 ? options.shot_threshold : auto_shot_threshold(diffs);
  // Shots: [begin, end) ranges of frames; a frame whose difference exceeds the shot threshold
  // starts a new shot.
  std::size_t begin = 0;
  auto finish_shot = [&](std::size_t b, std::size_t e) {
    double sum = 0;
    std::size_t n = 0;
    for (std::size_t i = b + 1; i < e; ++i) {  // differences inside the shot
      sum += diffs[i];
      ++n;
    }
    if (n == 0) return;
    const double mean = sum / static_cast<double>(n);
    for (std::size_t i = b + 1; i < e; ++i)
      if (diffs[i] > options.k * mean) keys.push_back(i - 1);
  };
  for (std::size_t i = 1; i < diffs.size(); ++i) {
    if (diffs[i] > shot_thr) {
      finish_shot(begin, i);
      keys.push_back(i - 1);  // the frame just before a shot boundary
      begin = i;
    }
  }
  finish_shot(begin, diffs.size());
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  return keys;
}

}  // namespace builtscene::barcode
