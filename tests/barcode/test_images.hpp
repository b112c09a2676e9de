#pragma once
// Helpers that build test images with known content (closed-form truth).
#include <cmath>
#include <string>

#include <opencv2/imgproc.hpp>

#include "synth/warehouse_scene.hpp"

namespace builtscene::barcode::test {

// `symbol` turned so that its scan direction points at `angle_deg` (image coordinates: x right,
// y down, angle from +x towards +y), centred on a canvas of the given size filled with `bg`.
inline cv::Mat rotated_on_canvas(const cv::Mat& symbol, double angle_deg, cv::Size canvas, int bg = 255) {
  cv::Mat out(canvas, CV_8UC1, cv::Scalar(bg));
  // getRotationMatrix2D turns counter-clockwise on screen for positive angles; a scan direction
  // at +angle (clockwise on screen with y down) therefore needs -angle.
  const cv::Point2f c(symbol.cols / 2.0f, symbol.rows / 2.0f);
  cv::Mat R = cv::getRotationMatrix2D(c, -angle_deg, 1.0);
  R.at<double>(0, 2) += canvas.width / 2.0 - c.x;
  R.at<double>(1, 2) += canvas.height / 2.0 - c.y;
  cv::Mat mask(symbol.size(), CV_8UC1, cv::Scalar(255)), warped_mask;
  cv::Mat warped;
  cv::warpAffine(symbol, warped, R, canvas, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(255));
  cv::warpAffine(mask, warped_mask, R, canvas, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar(0));
  warped.copyTo(out, warped_mask);
  return out;
}

// Difference between two undirected angles in degrees (period 180).
inline double angle_error(double a, double b) {
  double d = std::fmod(std::abs(a - b), 180.0);
  return std::min(d, 180.0 - d);
}

}  // namespace builtscene::barcode::test
