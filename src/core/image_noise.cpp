#include "core/image_noise.hpp"

#include <array>
#include <cstdint>
#include <cstdlib>

namespace builtscene {

double estimate_image_noise_sigma(const cv::Mat& gray, int step) {
  CV_Assert(gray.type() == CV_8UC1 && step >= 1);
  if (gray.rows < 3 || gray.cols < 3) return 0.0;
  // |response| is an integer in [0, 16 * 255]: a histogram gives the exact median in one pass.
  constexpr int kMax = 16 * 255;
  std::array<std::uint32_t, kMax + 1> hist{};
  std::uint64_t n = 0;
  for (int y = 1; y + 1 < gray.rows; y += step) {
    const std::uint8_t* a = gray.ptr<std::uint8_t>(y - 1);
    const std::uint8_t* b = gray.ptr<std::uint8_t>(y);
    const std::uint8_t* c = gray.ptr<std::uint8_t>(y + 1);
    for (int x = 1; x + 1 < gray.cols; x += step) {
      const int r = (a[x - 1] + a[x + 1] + c[x - 1] + c[x + 1]) - 2 * (a[x] + c[x] + b[x - 1] + b[x + 1]) + 4 * b[x];
      ++hist[static_cast<std::size_t>(std::abs(r))];
      ++n;
    }
  }
  const std::uint64_t half = (n + 1) / 2;
  std::uint64_t seen = 0;
  int median = 0;
  for (int v = 0; v <= kMax; ++v) {
    seen += hist[static_cast<std::size_t>(v)];
    if (seen >= half) {
      median = v;
      break;
    }
  }
  // For Gaussian noise the median of |response| is 0.6745 of its standard deviation (6 sigma).
  // The +0.5 centres the integer bin; it matters only for near-noiseless images.
  return (median + 0.5) / (0.6745 * 6.0);
}

}  // namespace builtscene
