#include "features/keypoint_distribution.hpp"

#include <algorithm>
#include <cmath>

namespace builtscene {

void distribute_quadtree(const std::vector<cv::KeyPoint>& keypoints, const cv::Rect2f& bounds, int wanted,
                         std::vector<cv::KeyPoint>& out, QuadtreeScratch& scratch) {
  out.clear();
  if (wanted <= 0 || keypoints.empty()) return;
  if (static_cast<int>(keypoints.size()) <= wanted) {
    out = keypoints;
    return;
  }
  // Every cell owns a range [begin, end) of `members` (keypoint indices, in input order);
  // splitting a cell partitions its range stably into its four quadrants, so no cell
  // allocates and a keypoint's order inside its cell is always its input order.
  auto& cells = scratch.cells;
  auto& members = scratch.members;
  auto& tmp = scratch.tmp;
  auto& heap = scratch.heap;
  auto& split_away = scratch.split_away;
  cells.clear();
  heap.clear();
  split_away.clear();
  members.resize(keypoints.size());
  tmp.resize(keypoints.size());

  // Start from square-ish roots so a wide image is not split into thin slices.
  const int roots = std::max(1, static_cast<int>(std::lround(bounds.width / std::max(1.0f, bounds.height))));
  const float root_w = bounds.width / static_cast<float>(roots);
  {
    auto root_of = [&](int i) {
      return std::clamp(static_cast<int>((keypoints[static_cast<std::size_t>(i)].pt.x - bounds.x) / root_w), 0, roots - 1);
    };
    std::vector<int>& count = scratch.root_count;
    count.assign(static_cast<std::size_t>(roots) + 1, 0);
    for (int i = 0; i < static_cast<int>(keypoints.size()); ++i) ++count[static_cast<std::size_t>(root_of(i)) + 1];
    for (int r = 0; r < roots; ++r) count[static_cast<std::size_t>(r) + 1] += count[static_cast<std::size_t>(r)];
    std::vector<int>& fill = scratch.root_fill;
    fill.assign(count.begin(), count.end() - 1);
    for (int i = 0; i < static_cast<int>(keypoints.size()); ++i) members[static_cast<std::size_t>(fill[static_cast<std::size_t>(root_of(i))]++)] = i;
    for (int r = 0; r < roots; ++r) {
      const int b = count[static_cast<std::size_t>(r)], e = count[static_cast<std::size_t>(r) + 1];
      if (b == e) continue;
      cells.push_back({cv::Rect2f(bounds.x + root_w * static_cast<float>(r), bounds.y, root_w, bounds.height), b, e});
    }
  }

  // Largest cell first (ties: the more crowded one), i.e. the tree is refined breadth-first,
  // level by level, so a dense cluster cannot keep the budget away from sparse regions.
  auto by_size = [&cells](int a, int b) {
    const auto& ca = cells[static_cast<std::size_t>(a)];
    const auto& cb = cells[static_cast<std::size_t>(b)];
    const float aa = ca.box.area(), ab = cb.box.area();
    if (aa != ab) return aa < ab;
    return ca.size() < cb.size();
  };
  auto push = [&](int i) {
    heap.push_back(i);
    std::push_heap(heap.begin(), heap.end(), by_size);
  };
  for (int i = 0; i < static_cast<int>(cells.size()); ++i)
    if (cells[static_cast<std::size_t>(i)].size() > 1) push(i);

  split_away.assign(cells.size(), 0);
  int live = static_cast<int>(cells.size());
  while (live < wanted && !heap.empty()) {
    std::pop_heap(heap.begin(), heap.end(), by_size);
    const int idx = heap.back();
    heap.pop_back();
    const QuadtreeScratch::Cell parent = cells[static_cast<std::size_t>(idx)];
    const float hw = parent.box.width * 0.5f;
    const float hh = parent.box.height * 0.5f;
    if (hw < 1.0f || hh < 1.0f) continue;  // too small to split: keep as a leaf
    int count[4] = {0, 0, 0, 0};
    auto quadrant = [&](int m) {
      const auto& p = keypoints[static_cast<std::size_t>(m)].pt;
      return (p.x >= parent.box.x + hw ? 1 : 0) + (p.y >= parent.box.y + hh ? 2 : 0);
    };
    for (int j = parent.begin; j < parent.end; ++j) ++count[quadrant(members[static_cast<std::size_t>(j)])];
    int start[4];
    start[0] = parent.begin;
    for (int q = 1; q < 4; ++q) start[q] = start[q - 1] + count[q - 1];
    int fill[4] = {start[0], start[1], start[2], start[3]};
    for (int j = parent.begin; j < parent.end; ++j) {
      const int m = members[static_cast<std::size_t>(j)];
      tmp[static_cast<std::size_t>(fill[quadrant(m)]++)] = m;
    }
    std::copy(tmp.begin() + parent.begin, tmp.begin() + parent.end, members.begin() + parent.begin);
    split_away[static_cast<std::size_t>(idx)] = 1;
    --live;
    for (int q = 0; q < 4; ++q) {
      if (count[q] == 0) continue;
      cells.push_back({cv::Rect2f(parent.box.x + static_cast<float>(q % 2) * hw, parent.box.y + static_cast<float>(q / 2) * hh, hw, hh),
                       start[q], start[q] + count[q]});
      split_away.push_back(0);
      ++live;
      if (count[q] > 1) push(static_cast<int>(cells.size()) - 1);
    }
  }

  out.reserve(static_cast<std::size_t>(live));
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (split_away[i]) continue;
    int best = members[static_cast<std::size_t>(cells[i].begin)];
    for (int j = cells[i].begin; j < cells[i].end; ++j) {
      const int m = members[static_cast<std::size_t>(j)];
      if (keypoints[static_cast<std::size_t>(m)].response > keypoints[static_cast<std::size_t>(best)].response) best = m;
    }
    out.push_back(keypoints[static_cast<std::size_t>(best)]);
  }
  if (static_cast<int>(out.size()) > wanted) {
    std::nth_element(out.begin(), out.begin() + wanted, out.end(),
                     [](const cv::KeyPoint& a, const cv::KeyPoint& b) { return a.response > b.response; });
    out.resize(static_cast<std::size_t>(wanted));
  }
}

std::vector<cv::KeyPoint> distribute_quadtree(const std::vector<cv::KeyPoint>& keypoints, const cv::Rect2f& bounds,
                                              int wanted) {
  std::vector<cv::KeyPoint> out;
  QuadtreeScratch scratch;
  distribute_quadtree(keypoints, bounds, wanted, out, scratch);
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
