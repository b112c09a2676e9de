#pragma once
// AprilTag detection with libapriltag (tag36h11 by default; any family libapriltag ships).
// Corners are in OpenCV pixel coordinates (the centre of the top-left pixel is (0, 0)),
// ordered as libapriltag gives them: counter-clockwise around the tag as seen in the image
// when the tag is upright, starting at the tag's bottom-left corner.
#include <array>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace builtscene {

struct TagDetection {
  int id = -1;
  int hamming = 0;
  double decision_margin = 0;
  Eigen::Vector2d center;
  std::array<Eigen::Vector2d, 4> corners;
};

struct AprilTagOptions {
  std::string family = "tag36h11";
  float decimate = 1.0f;      // quad_decimate: >1 is faster, less accurate on small tags
  float blur_sigma = 0.0f;
  int threads = 1;
  bool refine_edges = true;
  int max_hamming = 1;        // reject detections with more corrected bits
  int upsample = 1;           // 2: detect on a 2x (bicubic) image; finds tags of ~15 px, 4x slower
};

class AprilTagDetector {
 public:
  explicit AprilTagDetector(AprilTagOptions options = {});  // InputError for an unknown family
  ~AprilTagDetector();
  AprilTagDetector(const AprilTagDetector&) = delete;
  AprilTagDetector& operator=(const AprilTagDetector&) = delete;

  // gray: CV_8UC1 (a colour image is converted).
  std::vector<TagDetection> detect(const cv::Mat& image) const;

  const AprilTagOptions& options() const { return options_; }
  // The tag's bits as an image (black border included), from libapriltag's own codes: for
  // rendering test scenes. One pixel per bit cell, total_width cells wide.
  cv::Mat render_tag(int id) const;

 private:
  AprilTagOptions options_;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace builtscene
