#pragma once
// One frame processed in localization mode, as the per-frame consumers of `localize` see it
// (2D pose on the occupancy grid, points of interest, marker measurements).
#include <cstddef>
#include <functional>
#include <optional>

#include <opencv2/core.hpp>

#include "core/se3.hpp"

namespace builtscene::app {

struct LocalizedFrame {
  std::size_t index = 0;
  double timestamp = 0;
  bool tracked = false;
  std::optional<SE3> T_wc;  // camera to world (the map's world), when tracked
  const cv::Mat& image;     // as read (colour or gray)
  const cv::Mat& depth;     // metres, CV_32F; empty when the depth image was unreadable
};
using FrameObserver = std::function<void(const LocalizedFrame&)>;

}  // namespace builtscene::app
