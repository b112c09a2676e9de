#include "features/brief_smoothing.hpp"

#include <algorithm>

#include <opencv2/imgproc.hpp>

namespace builtscene {
namespace {

constexpr int kRadius = 3;

// The weights of |offset| 3, 2, 1 and 0, as constants: multiplying by a known small number
// compiles to shifts and adds, where a run-time weight needs the slow 32-bit vector multiply.
// Derived as OpenCV derives its bit-exact kernel: 256 exp(-i^2 / 8) / sum for i = 3, 2, 1 is
// 17.96, 33.55, 48.82; rounded from the tail inwards with the rounding error carried (18,
// carry -0.04; 33.51 -> 34, carry -0.49; 48.33 -> 48), the centre taking the rest (56).
constexpr std::uint32_t kW3 = 18, kW2 = 34, kW1 = 48, kW0 = 56;
static_assert(kW0 + 2 * (kW1 + kW2 + kW3) == 256);

int reflect101(int i, int n) { return i < 0 ? -i : (i >= n ? 2 * (n - 1) - i : i); }

// The two passes as plain loops over contiguous rows, which GCC vectorizes; the clones give
// the AVX2 build on machines that have it (16 pixels per instruction in the 16-bit pass).
// Not under ThreadSanitizer: the clones' ifunc resolver runs at load time, before the TSan
// runtime is up, and the instrumented resolver crashed every program at start.
#ifdef __SANITIZE_THREAD__
#define BS_AVX2_CLONES
#else
#define BS_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
#endif
BS_AVX2_CLONES
void horizontal_pass(const std::uint8_t* __restrict padded, std::uint16_t* __restrict out, int n) {
  for (int x = 0; x < n; ++x) {
    const auto a = static_cast<std::uint16_t>(padded[x] + padded[x + 6]);
    const auto b = static_cast<std::uint16_t>(padded[x + 1] + padded[x + 5]);
    const auto c = static_cast<std::uint16_t>(padded[x + 2] + padded[x + 4]);
    out[x] = static_cast<std::uint16_t>(kW3 * a + kW2 * b + kW1 * c + kW0 * padded[x + 3]);
  }
}

BS_AVX2_CLONES
void vertical_pass(const std::uint16_t* __restrict r0, const std::uint16_t* __restrict r1,
                   const std::uint16_t* __restrict r2, const std::uint16_t* __restrict r3,
                   const std::uint16_t* __restrict r4, const std::uint16_t* __restrict r5,
                   const std::uint16_t* __restrict r6, std::uint8_t* __restrict out, int n) {
  for (int x = 0; x < n; ++x) {
    const std::uint32_t s = kW3 * (static_cast<std::uint32_t>(r0[x]) + r6[x]) +
                            kW2 * (static_cast<std::uint32_t>(r1[x]) + r5[x]) +
                            kW1 * (static_cast<std::uint32_t>(r2[x]) + r4[x]) + kW0 * static_cast<std::uint32_t>(r3[x]);
    out[x] = static_cast<std::uint8_t>((s + (1u << 15)) >> 16);
  }
}

}  // namespace

std::array<std::uint16_t, 7> brief_smoothing_kernel() {
  return {kW3, kW2, kW1, kW0, kW1, kW2, kW3};
}

void smooth_for_brief(const cv::Mat& src, cv::Mat& dst, std::vector<std::uint16_t>& scratch) {
  CV_Assert(src.type() == CV_8UC1);
  if (src.rows < kRadius + 1 || src.cols < kRadius + 1) {
    cv::GaussianBlur(src, dst, cv::Size(7, 7), 2, 2, cv::BORDER_REFLECT_101);
    return;
  }
  const int rows = src.rows, cols = src.cols;
  // The horizontal pass's rows live in a ring of 8 (row r at slot r % 8): every source row
  // an output row y needs, mirrored or not, lies in [y - 3, y + 3], so the ring keeps the
  // working set in the first-level cache. After the ring, one padded source row.
  constexpr int kRing = 8;
  const auto stride = static_cast<std::size_t>(cols);
  scratch.resize(kRing * stride + stride / 2 + 8);
  std::uint16_t* ring = scratch.data();
  auto* padded = reinterpret_cast<std::uint8_t*>(scratch.data() + kRing * stride);
  auto slot = [&](int r) { return ring + static_cast<std::size_t>(r % kRing) * stride; };
  int done = 0;  // source rows [0, done) have been through the horizontal pass
  auto horizontal_until = [&](int last) {
    for (; done <= last; ++done) {
      const std::uint8_t* s = src.ptr<std::uint8_t>(done);
      for (int i = 0; i < kRadius; ++i) {
        padded[i] = s[kRadius - i];
        padded[cols + kRadius + i] = s[cols - 2 - i];
      }
      std::copy(s, s + cols, padded + kRadius);
      horizontal_pass(padded, slot(done), cols);
    }
  };
  dst.create(rows, cols, CV_8UC1);
  auto row = [&](int y) { return slot(reflect101(y, rows)); };
  for (int y = 0; y < rows; ++y) {
    horizontal_until(std::min(y + kRadius, rows - 1));
    vertical_pass(row(y - 3), row(y - 2), row(y - 1), row(y), row(y + 1), row(y + 2), row(y + 3), dst.ptr<std::uint8_t>(y), cols);
  }
}

}  // namespace builtscene
