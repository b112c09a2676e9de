#include "io/tum_dataset.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "core/errors.hpp"

namespace builtscene {

std::vector<TimestampedPath> read_tum_list(const std::filesystem::path& list_file) {
  std::ifstream in(list_file);
  if (!in) throw_input_error(list_file, 0, "cannot open list file");
  std::vector<TimestampedPath> out;
  std::string line;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream ss(line);
    TimestampedPath e;
    std::string path;
    if (!(ss >> e.timestamp >> path) || !std::isfinite(e.timestamp))
      throw_input_error(list_file, line_no, "expected 'timestamp path'");
    e.path = path;
    out.push_back(std::move(e));
  }
  if (out.empty()) throw_input_error(list_file, 0, "no entries");
  return out;
}

std::vector<std::pair<std::size_t, std::size_t>> associate_timestamps(const std::vector<double>& a,
                                                                      const std::vector<double>& b,
                                                                      double max_difference) {
  // Candidate pairs within the window, found by a sorted sweep over b, then greedy by distance.
  std::vector<std::size_t> order_b(b.size());
  for (std::size_t i = 0; i < b.size(); ++i) order_b[i] = i;
  std::sort(order_b.begin(), order_b.end(), [&](std::size_t x, std::size_t y) { return b[x] < b[y]; });
  std::vector<double> sorted_b(b.size());
  for (std::size_t i = 0; i < b.size(); ++i) sorted_b[i] = b[order_b[i]];

  struct Candidate {
    double diff;
    std::size_t ia, ib;
  };
  std::vector<Candidate> candidates;
  for (std::size_t ia = 0; ia < a.size(); ++ia) {
    auto lo = std::lower_bound(sorted_b.begin(), sorted_b.end(), a[ia] - max_difference);
    for (auto it = lo; it != sorted_b.end() && *it <= a[ia] + max_difference; ++it) {
      const auto k = static_cast<std::size_t>(it - sorted_b.begin());
      candidates.push_back({std::abs(a[ia] - *it), ia, order_b[k]});
    }
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& x, const Candidate& y) { return x.diff < y.diff; });
  std::vector<bool> used_a(a.size(), false), used_b(b.size(), false);
  std::vector<std::pair<std::size_t, std::size_t>> out;
  for (const auto& c : candidates) {
    if (used_a[c.ia] || used_b[c.ib]) continue;
    used_a[c.ia] = used_b[c.ib] = true;
    out.emplace_back(c.ia, c.ib);
  }
  std::sort(out.begin(), out.end());
  return out;
}

TumDataset TumDataset::open(const std::filesystem::path& dir, const std::filesystem::path& camera_file,
                            double max_difference) {
  if (!std::filesystem::is_directory(dir)) throw_input_error(dir, 0, "dataset folder does not exist");
  TumDataset ds;
  ds.root_ = dir;
  ds.settings_ = load_camera_settings(camera_file.empty() ? dir / "camera.yaml" : camera_file);
  const auto rgb = read_tum_list(dir / "rgb.txt");
  const auto depth = read_tum_list(dir / "depth.txt");
  std::vector<double> ta, tb;
  for (const auto& e : rgb) ta.push_back(e.timestamp);
  for (const auto& e : depth) tb.push_back(e.timestamp);
  for (const auto& [ia, ib] : associate_timestamps(ta, tb, max_difference))
    ds.frames_.push_back({rgb[ia].timestamp, depth[ib].timestamp, rgb[ia].path, depth[ib].path});
  if (ds.frames_.empty())
    throw_input_error(dir / "depth.txt", 0, "no depth timestamp within " + std::to_string(max_difference) +
                                                " s of any colour timestamp in rgb.txt");
  return ds;
}

Trajectory TumDataset::groundtruth() const { return read_tum_trajectory(root_ / "groundtruth.txt"); }

static std::filesystem::path resolve(const std::filesystem::path& root, const std::filesystem::path& p) {
  return p.is_absolute() ? p : root / p;
}

cv::Mat TumDataset::load_rgb(std::size_t i) const {
  const auto path = resolve(root_, frames_.at(i).rgb);
  cv::Mat img = cv::imread(path.string(), cv::IMREAD_COLOR);
  if (img.empty()) throw_input_error(path, 0, "cannot read colour image");
  return img;
}

cv::Mat TumDataset::load_depth(std::size_t i) const {
  const auto path = resolve(root_, frames_.at(i).depth);
  cv::Mat raw = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  if (raw.empty()) throw_input_error(path, 0, "cannot read depth image");
  if (raw.type() != CV_16UC1) throw_input_error(path, 0, "depth must be a 16-bit single-channel PNG");
  const auto& cam = settings_.camera;
  if (raw.cols != cam.width || raw.rows != cam.height)
    throw_input_error(path, 0, "depth is " + std::to_string(raw.cols) + "x" + std::to_string(raw.rows) +
                                   ", camera.yaml says " + std::to_string(cam.width) + "x" + std::to_string(cam.height));
  cv::Mat depth;
  raw.convertTo(depth, CV_32F, 1.0 / settings_.depth_map_factor);
  return depth;
}

}  // namespace builtscene
