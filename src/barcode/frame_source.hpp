#pragma once
// Frames of a scan, from a video file (OpenCV VideoCapture: MJPG .avi, MP4 where the FFmpeg
// backend can read it) or from a folder of numbered images (png, jpg, bmp, tif, pgm, ppm).
// Read problems are InputErrors whose message names the file: missing, unreadable, empty
// folder, a file that is not a decodable image, a video with no frames or one that ends before
// the frame count in its header.
#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace builtscene::barcode {

// One frame as the source holds it: the compressed bytes where the format allows (MJPG video
// packets, image files), so that skipping costs nothing and decoding can run on worker threads;
// otherwise the decoded image.
struct EncodedFrame {
  std::vector<uchar> bytes;
  cv::Mat image;             // set when bytes are not available
  std::filesystem::path origin;  // the file it came from (for messages)
  std::size_t index = 0;
};

// Gray image of a frame, shrunk by `reduce` (1, 2, 4 or 8; JPEG decodes at that scale directly).
// Throws InputError naming the origin when the bytes are not a decodable image.
cv::Mat decode_gray(const EncodedFrame& frame, int reduce = 1);

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  // Opens a video file or an image folder; throws InputError.
  static std::unique_ptr<FrameSource> open(const std::filesystem::path& path);

  // Frames the source says it holds (the header's count for videos; exact for folders).
  virtual std::size_t expected_frames() const = 0;
  // Next frame (BGR, 8-bit). False at the end; InputError on a frame that cannot be read.
  virtual bool read(cv::Mat& frame) = 0;
  // Next frame without decoding where the format allows. False at the end.
  virtual bool read_encoded(EncodedFrame& frame) = 0;
  // Steps over the next frame without decoding it where the format allows. False at the end.
  virtual bool skip() = 0;
  // Back to the first frame.
  virtual void rewind() = 0;
  // Index of the next frame read() or skip() would return.
  virtual std::size_t position() const = 0;
  // The file the next frame comes from (the video itself, or the image in a folder).
  virtual std::filesystem::path current_file() const = 0;
  const std::filesystem::path& path() const { return path_; }

 protected:
  explicit FrameSource(std::filesystem::path path) : path_(std::move(path)) {}
  std::filesystem::path path_;
};

// Image files of a folder in natural order ("2.png" before "10.png"); other files ignored.
std::vector<std::filesystem::path> list_image_files(const std::filesystem::path& dir);

}  // namespace builtscene::barcode
