#pragma once
// Reads a TUM-layout sequence frame by frame for the commands that track it (slam, localize),
// with the bad-input rules they share: a frame whose timestamp is not after the previous one, or
// whose colour image cannot be read, is skipped; a frame whose depth image cannot be read is
// kept without depth. Each case is logged with the frame and counted for the JSON summary.
#include <cstddef>
#include <limits>
#include <optional>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "io/tum_dataset.hpp"

namespace builtscene::app {

struct RgbdInputFrame {
  std::size_t index = 0;
  double timestamp = 0;
  cv::Mat rgb;
  cv::Mat depth;  // metres, CV_32F; empty when the depth image was unreadable
};

class RgbdFrameReader {
 public:
  // The first `count` frames of `data` (which must outlive the reader).
  RgbdFrameReader(const TumDataset& data, std::size_t count) : data_(data), count_(count) {}

  // The next usable frame, or nothing at the end of the sequence.
  std::optional<RgbdInputFrame> next();
  // Index of the next frame to read (for progress).
  std::size_t position() const { return next_; }
  std::size_t count() const { return count_; }
  // Frames handed out so far.
  long delivered() const { return delivered_; }
  // `bad_input` of the JSON summary: unreadable_rgb, bad_depth, timestamp_out_of_order.
  nlohmann::json bad_input() const;

 private:
  const TumDataset& data_;
  std::size_t count_;
  std::size_t next_ = 0;
  long delivered_ = 0, unreadable_rgb_ = 0, bad_depth_ = 0, out_of_order_ = 0;
  double last_timestamp_ = -std::numeric_limits<double>::infinity();
};

}  // namespace builtscene::app
