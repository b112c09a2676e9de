#pragma once
// A TUM RGB-D layout folder: rgb.txt and depth.txt (`timestamp path` lines), colour images of
// any format OpenCV reads, 16-bit depth PNGs scaled by DepthMapFactor, optional
// groundtruth.txt and camera.yaml. Colour and depth are associated one-to-one by nearest
// timestamp within max_difference (0.02 s), closest pairs first, as TUM's associate.py does.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "core/camera.hpp"
#include "io/trajectory.hpp"

namespace builtscene {

struct RgbdFrameEntry {
  double timestamp = 0;        // the colour image's
  double depth_timestamp = 0;
  std::filesystem::path rgb;   // absolute or relative to the dataset root as listed
  std::filesystem::path depth;
};

struct TimestampedPath {
  double timestamp = 0;
  std::filesystem::path path;
};

// Reads a TUM list file; InputError with file:line on a malformed line or a missing file.
std::vector<TimestampedPath> read_tum_list(const std::filesystem::path& list_file);

// Pairs (index in a, index in b) with |ta - tb| <= max_difference, each index used once,
// the closest pairs chosen first; sorted by a's index.
std::vector<std::pair<std::size_t, std::size_t>> associate_timestamps(const std::vector<double>& a,
                                                                      const std::vector<double>& b,
                                                                      double max_difference);

class TumDataset {
 public:
  // camera_file empty -> DIR/camera.yaml. Throws InputError on a bad folder.
  static TumDataset open(const std::filesystem::path& dir, const std::filesystem::path& camera_file = {},
                         double max_difference = 0.02);

  std::size_t size() const { return frames_.size(); }
  const RgbdFrameEntry& entry(std::size_t i) const { return frames_.at(i); }
  const std::vector<RgbdFrameEntry>& entries() const { return frames_; }
  const RgbdCameraSettings& settings() const { return settings_; }
  const std::filesystem::path& root() const { return root_; }
  bool has_groundtruth() const { return std::filesystem::exists(root_ / "groundtruth.txt"); }
  Trajectory groundtruth() const;

  // Colour image as 8-bit BGR; throws InputError naming the file when unreadable.
  cv::Mat load_rgb(std::size_t i) const;
  // Depth in metres (CV_32F, 0 = no reading); requires a 16-bit single-channel image of the
  // colour image's size; NaN/negative never appear in the output.
  cv::Mat load_depth(std::size_t i) const;

 private:
  std::filesystem::path root_;
  RgbdCameraSettings settings_;
  std::vector<RgbdFrameEntry> frames_;
};

}  // namespace builtscene
