#include "features/keypoint_distribution.hpp"

#include <algorithm>
#include <queue>

namespace builtscene {
namespace {

struct Cell {
  cv::Rect2f box;
  std::vector<int> members;  // indices into the keypoint vector
};

}  // namespace

std::vector<cv::KeyPoint> distribute_quadtree(const std::vector<cv::KeyPoint>& keypoints, const cv::Rect2f& bounds,
                                              int wanted) {
  if (wanted <= 0 || keypoints.empty()) return {};
  if (static_cast<int>(keypoints.size()) <= wanted) return keypoints;

  std::vector<Cell> cells;
  // Start from square-ish roots so a wide image is not split into thin slices.
  const int roots = std::max(1, static_cast<int>(std::lround(bounds.width / std::max(1.0f, bounds.height))));
  const float root_w = bounds.width / static_cast<float>(roots);
  for (int r = 0; r < roots; ++r)
    cells.push_back({cv::Rect2f(bounds.x + root_w * static_cast<float>(r), bounds.y, root_w, bounds.height), {}});
  for (int i = 0; i < static_cast<int>(keypoints.size()); ++i) {
    const int r = std::clamp(static_cast<int>((keypoints[i].pt.x - bounds.x) / root_w), 0, roots - 1);
    cells[static_cast<std::size_t>(r)].members.push_back(i);
  }
  std::erase_if(cells, [](const Cell& c) { return c.members.empty(); });

  // Largest cell first (ties: the more crowded one), i.e. the tree is refined breadth-first,
  // level by level, so a dense cluster cannot keep the budget away from sparse regions.
  auto by_size = [&cells](int a, int b) {
    const float aa = cells[a].box.area(), ab = cells[b].box.area();
    if (aa != ab) return aa < ab;
    return cells[a].members.size() < cells[b].members.size();
  };
  std::priority_queue<int, std::vector<int>, decltype(by_size)> heap(by_size);
  for (int i = 0; i < static_cast<int>(cells.size()); ++i)
    if (cells[i].members.size() > 1) heap.push(i);

  std::vector<bool> split_away(cells.size(), false);
  int live = static_cast<int>(cells.size());
  while (live < wanted && !heap.empty()) {
    const int idx = heap.top();
    heap.pop();
    const float hw = cells[static_cast<std::size_t>(idx)].box.width * 0.5f;
    const float hh = cells[static_cast<std::size_t>(idx)].box.height * 0.5f;
    if (hw < 1.0f || hh < 1.0f) continue;  // too small to split: keep as a leaf
    const Cell parent = std::move(cells[static_cast<std::size_t>(idx)]);  // its slot is retired below
    Cell child[4];
    for (int q = 0; q < 4; ++q)
      child[q].box = cv::Rect2f(parent.box.x + (q % 2) * hw, parent.box.y + static_cast<float>(q / 2) * hh, hw, hh);
    for (int m : parent.members) {
      const auto& p = keypoints[static_cast<std::size_t>(m)].pt;
      const int q = (p.x >= parent.box.x + hw ? 1 : 0) + (p.y >= parent.box.y + hh ? 2 : 0);
      child[q].members.push_back(m);
    }
    split_away[static_cast<std::size_t>(idx)] = true;
    --live;
    for (auto& c : child) {
      if (c.members.empty()) continue;
      cells.push_back(std::move(c));
      split_away.push_back(false);
      ++live;
      if (cells.back().members.size() > 1) heap.push(static_cast<int>(cells.size()) - 1);
    }
  }

  std::vector<cv::KeyPoint> out;
  out.reserve(static_cast<std::size_t>(live));
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (split_away[i]) continue;
    int best = cells[i].members.front();
    for (int m : cells[i].members)
      if (keypoints[static_cast<std::size_t>(m)].response > keypoints[static_cast<std::size_t>(best)].response) best = m;
    out.push_back(keypoints[static_cast<std::size_t>(best)]);
  }
  if (static_cast<int>(out.size()) > wanted) {
    std::nth_element(out.begin(), out.begin() + wanted, out.end(),
                     [](const cv::KeyPoint& a, const cv::KeyPoint& b) { return a.response > b.response; });
    out.resize(static_cast<std::size_t>(wanted));
  }
  return out;
}

double grid_coverage(const std::vector<cv::KeyPoint>& keypoints, cv::Size image, int cols, int rows) {
  if (cols <= 0 || rows <= 0 || image.area() <= 0) return 0.0;
  std::vector<char> hit(static_cast<std::size_t>(cols * rows), 0);
  for (const auto& k : keypoints) {
    const int c = std::clamp(static_cast<int>(k.pt.x * static_cast<float>(cols) / static_cast<float>(image.width)), 0, cols - 1);
    const int r = std::clamp(static_cast<int>(k.pt.y * static_cast<float>(rows) / static_cast<float>(image.height)), 0, rows - 1);
    hit[static_cast<std::size_t>(r * cols + c)] = 1;
  }
  return static_cast<double>(std::count(hit.begin(), hit.end(), 1)) / static_cast<double>(hit.size());
}

}  // namespace builtscene
