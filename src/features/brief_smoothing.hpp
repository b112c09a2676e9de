#pragma once
// The smoothing BRIEF tests are made on: a 7 x 7 Gaussian with sigma 2 and mirrored borders
// (BORDER_REFLECT_101), in 8-bit fixed point. Its output equals cv::GaussianBlur(src, dst,
// {7, 7}, 2, 2, cv::BORDER_REFLECT_101) bit for bit (tests/features/brief_smoothing_test.cpp),
// in about a third of the time: OpenCV 4.6 has fast paths for 3- and 5-tap kernels only, and
// its generic 7-tap path made the smoothing a quarter of the ORB extraction time.
//
// The arithmetic is OpenCV's bit-exact scheme: kernel weights in 1/256 (the Gaussian rounded
// from the tails inwards, carrying the rounding error, the centre taking the remainder so the
// weights sum to 256), a horizontal pass into 16-bit sums, a vertical pass into 32-bit sums,
// and (sum + 2^15) >> 16 back to 8 bits. The weights are compile-time constants, so the
// multiplications become shifts and adds.
#include <array>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace builtscene {

// The seven fixed-point weights (sum 256), symmetric.
std::array<std::uint16_t, 7> brief_smoothing_kernel();

// `src` CV_8UC1; `dst` is (re)allocated to its size. A view into a larger image is mirrored at
// its own edges (cv::GaussianBlur would read the pixels outside it, unless BORDER_ISOLATED). `scratch` holds the 16-bit intermediate
// image and is reused across calls. Images smaller than 4 x 4 go to cv::GaussianBlur.
void smooth_for_brief(const cv::Mat& src, cv::Mat& dst, std::vector<std::uint16_t>& scratch);

}  // namespace builtscene
