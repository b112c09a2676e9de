#include "synth/rgbd_preview.hpp"

#include <cstdio>
#include <fstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/errors.hpp"
#include "io/trajectory.hpp"

namespace builtscene::synth {
namespace fs = std::filesystem;

cv::Mat rgbd_contact_sheet(const fs::path& dir, const std::vector<int>& frames, double scale, double max_depth) {
  std::vector<cv::Mat> rows;
  for (int i : frames) {
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", i);
    const cv::Mat rgb = cv::imread((dir / "rgb" / name).string(), cv::IMREAD_COLOR);
    const cv::Mat d16 = cv::imread((dir / "depth" / name).string(), cv::IMREAD_UNCHANGED);
    if (rgb.empty() || d16.empty()) throw InputError(located(dir / "rgb" / name, 0, "cannot read frame"));
    cv::Mat d8;
    d16.convertTo(d8, CV_8U, 255.0 / (max_depth * 5000.0));
    cv::Mat dc;
    cv::applyColorMap(d8, dc, cv::COLORMAP_JET);
    dc.setTo(cv::Scalar(0, 0, 0), d16 == 0);
    cv::Mat row;
    cv::hconcat(rgb, dc, row);
    rows.push_back(row);
  }
  cv::Mat sheet;
  cv::vconcat(rows, sheet);
  cv::resize(sheet, sheet, cv::Size(), scale, scale, cv::INTER_AREA);
  return sheet;
}

cv::Mat truth_map_picture(const fs::path& dir, int scale) {
  const cv::Mat pgm = cv::imread((dir / "truth_map.pgm").string(), cv::IMREAD_GRAYSCALE);
  if (pgm.empty()) throw InputError(located(dir / "truth_map.pgm", 0, "cannot read"));
  // origin from the YAML (lower-left corner of the bottom-left cell)
  double res = 0.05, ox = 0, oy = 0;
  std::ifstream y(dir / "truth_map.yaml");
  std::string line;
  while (std::getline(y, line)) {
    if (line.rfind("resolution:", 0) == 0) res = std::stod(line.substr(11));
    if (line.rfind("origin:", 0) == 0) std::sscanf(line.c_str(), "origin: [%lf, %lf", &ox, &oy);
  }
  cv::Mat big, bgr;
  cv::resize(pgm, big, cv::Size(), scale, scale, cv::INTER_NEAREST);
  cv::cvtColor(big, bgr, cv::COLOR_GRAY2BGR);
  if (fs::exists(dir / "groundtruth.txt")) {
    const auto traj = read_tum_trajectory(dir / "groundtruth.txt", false);
    std::vector<cv::Point> pts;
    for (const auto& p : traj) {
      const double col = (p.pose.translation().x() - ox) / res, row = pgm.rows - (p.pose.translation().y() - oy) / res;
      pts.emplace_back(static_cast<int>(col * scale), static_cast<int>(row * scale));
    }
    cv::polylines(bgr, pts, false, cv::Scalar(0, 0, 220), 1, cv::LINE_AA);
  }
  return bgr;
}

}  // namespace builtscene::synth
