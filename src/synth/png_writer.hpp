#pragma once
// A small, fast PNG encoder for the generator's frames: one fixed row filter (Sub) and a
// cheap deflate strategy instead of libpng's per-row filter search, which is most of the cost
// of cv::imwrite on noisy 640 x 480 frames. Output is standard PNG (any reader opens it) and
// deterministic.
#include <filesystem>
#include <string>

#include <opencv2/core.hpp>

namespace builtscene::synth {

// 8-bit BGR (CV_8UC3, stored as RGB), 8-bit gray (CV_8U) or 16-bit gray (CV_16U).
// Returns false when the file cannot be written.
bool write_png_fast(const std::filesystem::path& path, const cv::Mat& image);
std::string encode_png_fast(const cv::Mat& image);

}  // namespace builtscene::synth
