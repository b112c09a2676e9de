#include "barcode/region_detector.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace builtscene::barcode {

cv::Rect Region::bounds(const cv::Size& frame) const {
  return box.boundingRect() & cv::Rect(0, 0, frame.width, frame.height);
}

std::vector<Region> RegionDetector::detect(const cv::Mat& frame) const {
  std::vector<Region> regions;
  if (frame.empty()) return regions;
  cv::Mat gray;
  if (frame.channels() == 3) {
    cv::cvtColor(frame, gray, cv::COLOR_BGR2GRAY);
  } else {
    gray = frame;
  }
  const double s = std::clamp(options_.scale, 0.1, 1.0);
  cv::Mat small;
  if (s < 1.0) {
    cv::resize(gray, small, cv::Size(), s, s, cv::INTER_AREA);
  } else {
    small = gray;
  }
  cv::Mat binary;
  if (options_.mode == Binarization::threshold) {
    cv::threshold(small, binary, options_.threshold * 255.0, 255, cv::THRESH_BINARY);
    if (options_.dilate_px > 0) {
      // Dilating the bright label closes small gaps in its outline; bars stay as holes.
      cv::Mat k = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * options_.dilate_px + 1, 1));
      cv::morphologyEx(binary, binary, cv::MORPH_CLOSE, k);
    }
  } else if (options_.mode == Binarization::adaptive) {
    cv::adaptiveThreshold(small, binary, 255, cv::ADAPTIVE_THRESH_MEAN_C, cv::THRESH_BINARY,
                          options_.adaptive_block | 1, -options_.adaptive_offset);
  } else {
    cv::Mat edges;
    cv::Canny(small, edges, 40, 120);
    const int d = std::max(1, options_.dilate_px);
    cv::dilate(edges, edges, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * d + 1, 2 * d + 1)));
    binary = edges;
  }
  std::vector<std::vector<cv::Point>> contours;
  std::vector<cv::Vec4i> hierarchy;
  cv::findContours(binary, contours, hierarchy, cv::RETR_TREE, cv::CHAIN_APPROX_SIMPLE);
  const double area_scale = 1.0 / (s * s);
  for (std::size_t i = 0; i < contours.size(); ++i) {
    // Count direct children (holes inside this contour).
    int children = 0;
    for (int c = hierarchy[i][2]; c >= 0; c = hierarchy[static_cast<std::size_t>(c)][0]) ++children;
    if (children < options_.min_children) continue;
    const double area = cv::contourArea(contours[i]) * area_scale;
    if (area < options_.min_area) continue;
    std::vector<cv::Point> poly;
    cv::approxPolyDP(contours[i], poly, 0.03 * cv::arcLength(contours[i], true), true);
    if (static_cast<int>(poly.size()) > options_.max_vertices) continue;
    cv::RotatedRect box = cv::minAreaRect(contours[i]);
    const float lo = std::min(box.size.width, box.size.height), hi = std::max(box.size.width, box.size.height);
    if (lo <= 0 || hi / lo < options_.min_aspect || hi / lo > options_.max_aspect) continue;
    box.center = box.center * static_cast<float>(1.0 / s);
    const float grow = static_cast<float>(1.0 + 2.0 * options_.pad);
    box.size = cv::Size2f(box.size.width * grow / static_cast<float>(s) + 4.0f,
                          box.size.height * grow / static_cast<float>(s) + 4.0f);
    regions.push_back({box, children, area});
  }
  std::sort(regions.begin(), regions.end(), [](const Region& a, const Region& b) {
    if (std::abs(a.box.center.y - b.box.center.y) > 0.5f) return a.box.center.y < b.box.center.y;
    return a.box.center.x < b.box.center.x;
  });
  return regions;
}

}  // namespace builtscene::barcode
