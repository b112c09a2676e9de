#include "synth/truth_map.hpp"

#include <cmath>
#include <fstream>

#include <opencv2/imgproc.hpp>

#include "core/errors.hpp"

namespace builtscene::synth {

bool OccupancyTruth::cell_of(double x, double y, int& col, int& row) const {
  col = static_cast<int>(std::floor((x - origin_x) / resolution));
  row = static_cast<int>(std::floor((y - origin_y) / resolution));
  return col >= 0 && row >= 0 && col < width && row < height;
}

int OccupancyTruth::value_at(double x, double y) const {
  int c, r;
  if (!cell_of(x, y, c, r)) return -1;
  return at(c, r);
}

namespace {

// Separating-axis test between an axis-aligned square and a rotated rectangle footprint.
bool overlaps(double cx0, double cy0, double cx1, double cy1, const Eigen::Vector2d corners[4]) {
  double mnx = 1e30, mxx = -1e30, mny = 1e30, mxy = -1e30;
  for (int k = 0; k < 4; ++k) {
    mnx = std::min(mnx, corners[k].x());
    mxx = std::max(mxx, corners[k].x());
    mny = std::min(mny, corners[k].y());
    mxy = std::max(mxy, corners[k].y());
  }
  if (mxx <= cx0 || mnx >= cx1 || mxy <= cy0 || mny >= cy1) return false;
  const Eigen::Vector2d sq[4] = {{cx0, cy0}, {cx1, cy0}, {cx1, cy1}, {cx0, cy1}};
  for (int e = 0; e < 2; ++e) {
    const Eigen::Vector2d axis = Eigen::Vector2d(-(corners[e + 1] - corners[e]).y(), (corners[e + 1] - corners[e]).x());
    double a0 = 1e30, a1 = -1e30, b0 = 1e30, b1 = -1e30;
    for (int k = 0; k < 4; ++k) {
      const double pa = axis.dot(corners[k]), pb = axis.dot(sq[k]);
      a0 = std::min(a0, pa);
      a1 = std::max(a1, pa);
      b0 = std::min(b0, pb);
      b1 = std::max(b1, pb);
    }
    if (a1 <= b0 || b1 <= a0) return false;
  }
  return true;
}

}  // namespace

OccupancyTruth compute_truth_map(const Scene& scene, double band_min, double band_max, double resolution) {
  OccupancyTruth m;
  m.resolution = resolution;
  double x0 = 1e30, y0 = 1e30, x1 = -1e30, y1 = -1e30;
  for (const auto& f : scene.floor) {
    x0 = std::min(x0, f.x0);
    y0 = std::min(y0, f.y0);
    x1 = std::max(x1, f.x1);
    y1 = std::max(y1, f.y1);
  }
  const double margin = 0.5;
  m.origin_x = std::floor((x0 - margin) / resolution) * resolution;
  m.origin_y = std::floor((y0 - margin) / resolution) * resolution;
  m.width = static_cast<int>(std::ceil((x1 + margin - m.origin_x) / resolution));
  m.height = static_cast<int>(std::ceil((y1 + margin - m.origin_y) / resolution));
  m.cells.assign(static_cast<std::size_t>(m.width) * m.height, -1);
  for (int r = 0; r < m.height; ++r)
    for (int c = 0; c < m.width; ++c) {
      const double x = m.origin_x + (c + 0.5) * resolution, y = m.origin_y + (r + 0.5) * resolution;
      for (const auto& f : scene.floor)
        if (f.contains(x, y)) {
          m.cells[static_cast<std::size_t>(r) * m.width + c] = 0;
          break;
        }
    }
  for (const auto& b : scene.boxes) {
    if (!b.solid) continue;
    const double zb = b.center.z() - b.size.z() / 2, zt = b.center.z() + b.size.z() / 2;
    if (zt < band_min || zb > band_max) continue;
    const double c = std::cos(b.yaw), s = std::sin(b.yaw);
    const Eigen::Vector2d ex(c, s), ey(-s, c), ctr(b.center.x(), b.center.y());
    const double hx = b.size.x() / 2, hy = b.size.y() / 2;
    const Eigen::Vector2d corners[4] = {ctr - ex * hx - ey * hy, ctr + ex * hx - ey * hy, ctr + ex * hx + ey * hy, ctr - ex * hx + ey * hy};
    double mnx = 1e30, mxx = -1e30, mny = 1e30, mxy = -1e30;
    for (const auto& p : corners) {
      mnx = std::min(mnx, p.x());
      mxx = std::max(mxx, p.x());
      mny = std::min(mny, p.y());
      mxy = std::max(mxy, p.y());
    }
    const int c0 = std::max(0, static_cast<int>(std::floor((mnx - m.origin_x) / resolution)));
    const int c1 = std::min(m.width - 1, static_cast<int>(std::floor((mxx - m.origin_x) / resolution)));
    const int r0 = std::max(0, static_cast<int>(std::floor((mny - m.origin_y) / resolution)));
    const int r1 = std::min(m.height - 1, static_cast<int>(std::floor((mxy - m.origin_y) / resolution)));
    for (int r = r0; r <= r1; ++r)
      for (int cc = c0; cc <= c1; ++cc) {
        const double ax = m.origin_x + cc * resolution, ay = m.origin_y + r * resolution;
        if (overlaps(ax, ay, ax + resolution, ay + resolution, corners)) m.cells[static_cast<std::size_t>(r) * m.width + cc] = 100;
      }
  }
  return m;
}

void write_truth_map(const OccupancyTruth& map, const std::filesystem::path& pgm, const std::filesystem::path& yaml,
                     double band_min, double band_max) {
  {
    std::ofstream out(pgm, std::ios::binary);
    out << "P5\n# builtscene truth map, 254 free, 0 occupied, 205 unknown\n" << map.width << " " << map.height << "\n255\n";
    std::vector<unsigned char> row(static_cast<std::size_t>(map.width));
    for (int r = map.height - 1; r >= 0; --r) {  // row 0 of the image is the top (max y)
      for (int c = 0; c < map.width; ++c) {
        const int v = map.at(c, r);
        row[static_cast<std::size_t>(c)] = v < 0 ? 205 : (v >= 65 ? 0 : 254);
      }
      out.write(reinterpret_cast<const char*>(row.data()), static_cast<std::streamsize>(row.size()));
    }
    if (!out) throw Failure(located(pgm, 0, "cannot write truth map"));
  }
  std::ofstream y(yaml);
  y << "# Ground-truth occupancy of the height band [" << band_min << ", " << band_max
    << "] m, computed from scene.json\n"
    << "image: " << pgm.filename().string() << "\nresolution: " << map.resolution << "\norigin: [" << map.origin_x << ", "
    << map.origin_y << ", 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
  if (!y) throw Failure(located(yaml, 0, "cannot write truth map"));
}

cv::Mat clearance_map(const OccupancyTruth& map) {
  cv::Mat free(map.height, map.width, CV_8U);
  for (int r = 0; r < map.height; ++r)
    for (int c = 0; c < map.width; ++c) free.at<uint8_t>(r, c) = map.at(c, r) == 0 ? 255 : 0;
  cv::Mat dist;
  cv::distanceTransform(free, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  return dist * map.resolution;
}

}  // namespace builtscene::synth
