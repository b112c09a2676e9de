#include "slam/frame.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "slam/map_point.hpp"

namespace builtscene::slam {

std::shared_ptr<const FrameContext> FrameContext::make(const RgbdCameraSettings& s, const ScalePyramid& pyramid,
                                                       const DescriptorMetric& metric) {
  auto c = std::make_shared<FrameContext>();
  c->camera = s.camera;
  c->bf = s.bf;
  c->th_depth = s.close_depth();
  c->disparity_sigma = s.disparity_sigma;
  c->global_ba_disparity_sigma = s.global_ba_disparity_sigma;
  c->local_ba_disparity_sigma = s.local_ba_disparity_sigma;
  c->max_depth = s.max_depth;
  c->far_depth = s.far_depth;
  c->pyramid = pyramid;
  c->metric = metric;
  const auto& cam = s.camera;
  if (cam.has_distortion()) {
    const Eigen::Vector2d corners[4] = {{0, 0}, {cam.width, 0}, {0, cam.height}, {cam.width, cam.height}};
    Eigen::Vector2d u[4];
    for (int i = 0; i < 4; ++i) u[i] = cam.undistort_pixel(corners[i]);
    c->min_x = static_cast<float>(std::min(u[0].x(), u[2].x()));
    c->max_x = static_cast<float>(std::max(u[1].x(), u[3].x()));
    c->min_y = static_cast<float>(std::min(u[0].y(), u[1].y()));
    c->max_y = static_cast<float>(std::max(u[2].y(), u[3].y()));
  } else {
    c->max_x = static_cast<float>(cam.width);
    c->max_y = static_cast<float>(cam.height);
  }
  c->grid_scale_x = static_cast<float>(kGridCols) / (c->max_x - c->min_x);
  c->grid_scale_y = static_cast<float>(kGridRows) / (c->max_y - c->min_y);
  return c;
}

std::vector<int> FrameFeatures::in_area(float u, float v, float r, int min_level, int max_level) const {
  std::vector<int> out;
  const auto& c = *ctx;
  const int x0 = std::max(0, static_cast<int>(std::floor((u - c.min_x - r) * c.grid_scale_x)));
  const int x1 = std::min(FrameContext::kGridCols - 1, static_cast<int>(std::ceil((u - c.min_x + r) * c.grid_scale_x)));
  const int y0 = std::max(0, static_cast<int>(std::floor((v - c.min_y - r) * c.grid_scale_y)));
  const int y1 = std::min(FrameContext::kGridRows - 1, static_cast<int>(std::ceil((v - c.min_y + r) * c.grid_scale_y)));
  if (x0 > x1 || y0 > y1) return out;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const int cell = y * FrameContext::kGridCols + x;
      for (int k = grid_start[static_cast<std::size_t>(cell)]; k < grid_start[static_cast<std::size_t>(cell) + 1]; ++k) {
        const int i = grid_items[static_cast<std::size_t>(k)];
        const auto& kp = keys_un[static_cast<std::size_t>(i)];
        if (min_level >= 0 && kp.octave < min_level) continue;
        if (max_level >= 0 && kp.octave > max_level) continue;
        if (std::abs(kp.pt.x - u) <= r && std::abs(kp.pt.y - v) <= r) out.push_back(i);
      }
    }
  }
  return out;
}

Eigen::Vector3d FrameFeatures::unproject(std::size_t i) const {
  const auto& cam = ctx->camera;
  const double z = depth[i];
  const auto& p = keys_un[i].pt;
  return {(p.x - cam.cx) * z / cam.fx, (p.y - cam.cy) * z / cam.fy, z};
}

void build_feature_grid(FrameFeatures& f) {
  const auto& ctx = *f.ctx;
  const std::size_t n = f.keys_un.size();
  // Grid in CSR form: count, prefix sum, fill.
  const int cells = FrameContext::kGridCols * FrameContext::kGridRows;
  std::vector<int> cell_of(n, -1);
  f.grid_start.assign(static_cast<std::size_t>(cells) + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& p = f.keys_un[i].pt;
    const int gx = static_cast<int>(std::floor((p.x - ctx.min_x) * ctx.grid_scale_x));
    const int gy = static_cast<int>(std::floor((p.y - ctx.min_y) * ctx.grid_scale_y));
    if (gx < 0 || gy < 0 || gx >= FrameContext::kGridCols || gy >= FrameContext::kGridRows) continue;
    cell_of[i] = gy * FrameContext::kGridCols + gx;
    ++f.grid_start[static_cast<std::size_t>(cell_of[i]) + 1];
  }
  for (int c = 0; c < cells; ++c) f.grid_start[static_cast<std::size_t>(c) + 1] += f.grid_start[static_cast<std::size_t>(c)];
  f.grid_items.assign(static_cast<std::size_t>(f.grid_start.back()), -1);
  std::vector<int> fill(f.grid_start.begin(), f.grid_start.end() - 1);
  for (std::size_t i = 0; i < n; ++i)
    if (cell_of[i] >= 0) f.grid_items[static_cast<std::size_t>(fill[static_cast<std::size_t>(cell_of[i])]++)] = static_cast<int>(i);
}

std::shared_ptr<const FrameFeatures> make_rgbd_features(const cv::Mat& gray, const cv::Mat& depth_m,
                                                        std::shared_ptr<const FrameContext> ctx, FeatureExtractor& extractor) {
  auto f = std::make_shared<FrameFeatures>();
  f->ctx = ctx;
  extractor.extract(gray, f->keys, f->descriptors);
  const std::size_t n = f->keys.size();
  const auto& cam = ctx->camera;
  f->keys_un = f->keys;
  if (cam.has_distortion()) {
    for (auto& k : f->keys_un) {
      const Eigen::Vector2d u = cam.undistort_pixel({k.pt.x, k.pt.y});
      k.pt = cv::Point2f(static_cast<float>(u.x()), static_cast<float>(u.y()));
    }
  }
  f->depth.assign(n, -1.0f);
  f->u_right.assign(n, -1.0f);
  const bool depth_ok = !depth_m.empty() && depth_m.type() == CV_32F && depth_m.size() == gray.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (!depth_ok) break;
    const int x = cvRound(f->keys[i].pt.x), y = cvRound(f->keys[i].pt.y);
    if (x < 0 || y < 0 || x >= depth_m.cols || y >= depth_m.rows) continue;
    const float d = depth_m.at<float>(y, x);
    if (std::isfinite(d) && d > 0 && (ctx->max_depth <= 0 || d <= ctx->max_depth)) {
      f->depth[i] = d;
      f->u_right[i] = f->keys_un[i].pt.x - static_cast<float>(ctx->bf) / d;
    }
  }
  build_feature_grid(*f);
  return f;
}

Frame::Frame(long id_, double timestamp_, std::shared_ptr<const FrameFeatures> features)
    : id(id_), timestamp(timestamp_), f(std::move(features)) {
  points.assign(f->size(), nullptr);
  outlier.assign(f->size(), 0);
}

int Frame::matched_count() const {
  int n = 0;
  for (std::size_t i = 0; i < points.size(); ++i) n += points[i] && !outlier[i];
  return n;
}

int Frame::keep_inlier_matches() {
  int n = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i]) continue;
    if (outlier[i]) {
      points[i] = nullptr;
      outlier[i] = 0;
    } else {
      ++n;
    }
  }
  return n;
}

void Frame::clear_matches() {
  std::fill(points.begin(), points.end(), nullptr);
  std::fill(outlier.begin(), outlier.end(), 0);
}

}  // namespace builtscene::slam
