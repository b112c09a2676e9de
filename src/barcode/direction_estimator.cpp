#include "barcode/direction_estimator.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace builtscene::barcode {

std::optional<double> DirectionEstimator::scan_angle(const cv::Mat& image) const {
  if (image.empty() || image.rows < 8 || image.cols < 8) return std::nullopt;
  cv::Mat gray;
  if (image.channels() == 3) {
    cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  } else {
    gray = image;
  }
  // Angles do not depend on scale: large regions are estimated on a smaller copy.
  const double shrink = static_cast<double>(std::max(32, options_.max_side)) / std::max(gray.cols, gray.rows);
  if (shrink < 1.0) cv::resize(gray, gray, cv::Size(), shrink, shrink, cv::INTER_AREA);
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(gray, corners, options_.max_corners, options_.harris_quality, 2.0, cv::noArray(), 3,
                          /*useHarrisDetector=*/true, 0.04);
  if (corners.size() < 6) return std::nullopt;

  // Hough transform of the points: theta in 1-degree steps, rho in 2-pixel bins.
  constexpr int n_theta = 180;
  const double diag = std::hypot(gray.cols, gray.rows);
  const double rho_step = 2.0;
  const int n_rho = static_cast<int>(std::ceil(2.0 * diag / rho_step)) + 1;
  std::vector<int> acc(static_cast<std::size_t>(n_theta * n_rho), 0);
  // Single precision and a table per theta: the vote loop is the estimator's hot spot (corners x 180).
  std::vector<float> cs(n_theta), sn(n_theta);
  for (int t = 0; t < n_theta; ++t) {
    const double th = t * std::numbers::pi / 180.0;
    cs[static_cast<std::size_t>(t)] = static_cast<float>(std::cos(th) / rho_step);
    sn[static_cast<std::size_t>(t)] = static_cast<float>(std::sin(th) / rho_step);
  }
  // rho + diag >= 0, so adding 0.5 and truncating rounds to the nearest bin.
  const float offset = static_cast<float>(diag / rho_step) + 0.5f;
  for (const auto& p : corners) {
    int* row = acc.data();
    for (int t = 0; t < n_theta; ++t, row += n_rho) {
      const float rho = p.x * cs[static_cast<std::size_t>(t)] + p.y * sn[static_cast<std::size_t>(t)];
      ++row[static_cast<int>(rho + offset)];
    }
  }
  // Peaks: the strongest cells, each suppressing its neighbourhood (+-3 degrees, +-2 rho bins).
  struct Peak {
    int votes, t, r;
  };
  // Only the strongest few hundred cells can become peaks: find the vote count of the 400th
  // strongest from a histogram of counts, and collect only the cells at or above it.
  constexpr std::size_t kCandidates = 400;
  int max_votes = 0;
  for (const int v : acc) max_votes = std::max(max_votes, v);
  std::vector<std::size_t> per_count(static_cast<std::size_t>(max_votes) + 1, 0);
  for (const int v : acc) ++per_count[static_cast<std::size_t>(v)];
  int min_votes = max_votes;
  for (std::size_t above = 0; min_votes > 3; --min_votes) {
    above += per_count[static_cast<std::size_t>(min_votes)];
    if (above >= kCandidates) break;
  }
  min_votes = std::max(min_votes, 3);
  std::vector<Peak> cells;
  for (int t = 0; t < n_theta; ++t)
    for (int r = 0; r < n_rho; ++r) {
      const int v = acc[static_cast<std::size_t>(t * n_rho + r)];
      if (v >= min_votes) cells.push_back({v, t, r});
    }
  const auto stronger = [](const Peak& a, const Peak& b) {
    if (a.votes != b.votes) return a.votes > b.votes;
    if (a.t != b.t) return a.t < b.t;
    return a.r < b.r;
  };
  const std::size_t keep = std::min(cells.size(), kCandidates);
  std::partial_sort(cells.begin(), cells.begin() + static_cast<std::ptrdiff_t>(keep), cells.end(), stronger);
  cells.resize(keep);
  std::vector<Peak> peaks;
  for (const auto& c : cells) {
    if (static_cast<int>(peaks.size()) >= options_.max_peaks) break;
    bool near = false;
    for (const auto& p : peaks) {
      int dt = std::abs(p.t - c.t);
      dt = std::min(dt, n_theta - dt);
      if (dt <= 3 && std::abs(p.r - c.r) <= 2) {
        near = true;
        break;
      }
    }
    if (!near) peaks.push_back(c);
  }
  if (peaks.empty()) return std::nullopt;

  // Histogram of peak angles; the fullest bin (by count, then by votes) wins. Bins wrap at 180.
  const int bins = std::max(1, options_.angle_bins);
  const double bin_width = 180.0 / bins;
  std::vector<int> count(static_cast<std::size_t>(bins), 0);
  std::vector<int> votes(static_cast<std::size_t>(bins), 0);
  for (const auto& p : peaks) {
    const auto b = static_cast<std::size_t>(std::min(bins - 1, static_cast<int>(p.t / bin_width)));
    ++count[b];
    votes[b] += p.votes;
  }
  std::size_t best = 0;
  for (std::size_t b = 1; b < count.size(); ++b)
    if (count[b] > count[best] || (count[b] == count[best] && votes[b] > votes[best])) best = b;
  // Vote-weighted circular mean (period 180) of the peaks in the winning bin and its neighbours
  // that lie within one bin width of the strongest peak there (a direction near a bin edge
  // splits between two bins).
  const Peak* top = nullptr;
  for (const auto& p : peaks)
    if (static_cast<std::size_t>(std::min(bins - 1, static_cast<int>(p.t / bin_width))) == best &&
        (!top || p.votes > top->votes))
      top = &p;
  double sx = 0, sy = 0;
  for (const auto& p : peaks) {
    int dt = std::abs(p.t - top->t);
    dt = std::min(dt, n_theta - dt);
    if (dt > bin_width) continue;
    const double a = 2.0 * p.t * std::numbers::pi / 180.0;
    sx += p.votes * std::cos(a);
    sy += p.votes * std::sin(a);
  }
  double theta = std::atan2(sy, sx) * 90.0 / std::numbers::pi;  // normal of the bar-end lines
  if (theta < 0) theta += 180.0;
  // The lines through the bar ends run along the scan direction; their normal (theta) is the
  // bars' direction, so the scan direction is theta - 90.
  double scan = theta - 90.0;
  if (scan < 0) scan += 180.0;
  if (scan >= 180.0) scan -= 180.0;
  return scan;
}

cv::Mat DirectionEstimator::upright(const cv::Mat& gray, double scan_angle_deg) {
  const cv::Point2f c(gray.cols * 0.5f, gray.rows * 0.5f);
  // Turning the image by +angle (counter-clockwise in OpenCV's convention with y down) brings
  // a line at `angle` to the horizontal.
  cv::Mat R = cv::getRotationMatrix2D(c, scan_angle_deg, 1.0);
  const cv::Rect2f box = cv::RotatedRect(c, gray.size(), static_cast<float>(scan_angle_deg)).boundingRect2f();
  R.at<double>(0, 2) += box.width / 2.0 - c.x;
  R.at<double>(1, 2) += box.height / 2.0 - c.y;
  cv::Mat out;
  cv::warpAffine(gray, out, R, cv::Size(cvCeil(box.width), cvCeil(box.height)), cv::INTER_LINEAR,
                 cv::BORDER_CONSTANT, cv::Scalar::all(255));
  return out;
}

}  // namespace builtscene::barcode
