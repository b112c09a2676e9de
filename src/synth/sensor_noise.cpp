#include "synth/sensor_noise.hpp"

#include <array>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace builtscene::synth {
namespace {

// Gaussian values by the inverse CDF on a regular grid of quantiles: fixed, so identical on
// every platform (std::normal_distribution is implementation-defined).
template <int N>
const std::array<float, N>& gaussian_table() {
  static const std::array<float, N> table = [] {
    std::array<float, N> t{};
    for (int i = 0; i < N; ++i) {
      const double p = (i + 0.5) / N;
      // Acklam's rational approximation of the normal quantile.
      const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02, 1.383577518672690e+02, -3.066479806614716e+01, 2.506628277459239e+00};
      const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02, 6.680131188771972e+01, -1.328068155288572e+01};
      const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00, -2.549732539343734e+00, 4.374664141464968e+00, 2.938163982698783e+00};
      const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00, 3.754408661907416e+00};
      double x;
      if (p < 0.02425) {
        const double q = std::sqrt(-2 * std::log(p));
        x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) / ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
      } else if (p > 1 - 0.02425) {
        const double q = std::sqrt(-2 * std::log(1 - p));
        x = -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) / ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
      } else {
        const double q = p - 0.5, r = q * q;
        x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
            (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
      }
      t[static_cast<std::size_t>(i)] = static_cast<float>(x);
    }
    return t;
  }();
  return table;
}

}  // namespace

FrameRng::FrameRng(std::uint64_t seed, std::uint64_t frame, std::uint64_t stream)
    : s_(seed * 0xD1B54A32D192ED03ull ^ (frame + 1) * 0x9E3779B97F4A7C15ull ^ (stream + 7) * 0xC2B2AE3D27D4EB4Full) {}

float FrameRng::gaussian() {
  const std::uint64_t r = next();
  // Table lookup plus a uniform jitter inside the quantile cell.
  const auto& t = gaussian_table<4096>();
  const std::size_t i = static_cast<std::size_t>(r & 4095u);
  const float j = static_cast<float>((r >> 12) & 0xFFFF) / 65536.0f;
  const float lo = t[i], hi = i + 1 < 4096 ? t[i + 1] : t[i];
  return lo + (hi - lo) * j;
}

void FrameRng::gaussian4(float* out) {
  const auto& t = gaussian_table<65536>();
  const std::uint64_t r = next();
  out[0] = t[r & 0xFFFF];
  out[1] = t[(r >> 16) & 0xFFFF];
  out[2] = t[(r >> 32) & 0xFFFF];
  out[3] = t[(r >> 48) & 0xFFFF];
}

cv::Mat apply_kinect_noise(const cv::Mat& depth, const cv::Mat& incidence, const KinectNoiseModel& m, FrameRng& rng) {
  const int H = depth.rows, W = depth.cols;
  cv::Mat out(H, W, CV_32F, cv::Scalar(0));
  const double bf = m.baseline_m * m.focal_px;
  const float jump = static_cast<float>(m.edge_jump);
  // Neighbourhood extremes for the discontinuity test; "no surface" counts as a step.
  cv::Mat zmin, zmax, far_fill = depth.clone(), right_min;
  far_fill.setTo(1e9f, depth <= 0);
  cv::erode(depth, zmin, cv::Mat(), cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  cv::dilate(far_fill, zmax, cv::Mat(), cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  // Nearest surface among the next 12 pixels to the right (projector shadow candidates).
  constexpr int kShadow = 12;
  cv::erode(far_fill, right_min, cv::Mat::ones(1, kShadow, CV_8U), cv::Point(0, 0), 1, cv::BORDER_CONSTANT, cv::Scalar(1e9));
  float g[4];
  for (int y = 0; y < H; ++y) {
    const float* inc = incidence.ptr<float>(y);
    const float* zmn = zmin.ptr<float>(y);
    const float* zmx = zmax.ptr<float>(y);
    const float* rmin = right_min.ptr<float>(y);
    const float* drow = depth.ptr<float>(y);
    float* o = out.ptr<float>(y);
    for (int x = 0; x < W; ++x) {
      // Lateral noise: the reading comes from a slightly displaced point of the surface.
      rng.gaussian4(g);
      const int sx = std::clamp(x + static_cast<int>(std::lround(g[0] * m.lateral_sigma_px)), 0, W - 1);
      const int sy = std::clamp(y + static_cast<int>(std::lround(g[1] * m.lateral_sigma_px)), 0, H - 1);
      const float z = depth.at<float>(sy, sx);
      if (z <= 0.f || z < m.min_range || z > m.max_range) continue;
      // Discontinuities: the block matcher fails next to a depth step.
      const float zc = drow[x];
      if (zmn[x] <= 0.f || zmx[x] - zc > jump * zc || zc - zmn[x] > jump * zc) continue;
      // Projector shadow: a nearer surface a few pixels to the right hides the pattern.
      if (x + 1 < W && rmin[x + 1] < zc * (1.f - jump)) {
        bool shadow = false;
        for (int k = 1; k <= kShadow && x + k < W; ++k) {
          const float zn = drow[x + k];
          if (zn > 0.f && zn < zc * (1.f - jump) && k < bf * (1.0 / zn - 1.0 / zc) * 0.6 + 2) {
            shadow = true;
            break;
          }
        }
        if (shadow) continue;
      }
      const float c = inc[x];
      if (c < m.grazing_cos) continue;
      if (c < m.grazing_soft_cos && rng.uniform() > (c - m.grazing_cos) / (m.grazing_soft_cos - m.grazing_cos)) continue;
      if (rng.uniform() < m.dropout) continue;
      // Axial noise, then disparity quantization.
      const double zn = z + g[3] * KinectNoiseModel::axial_sigma(z);
      const double disp = bf / zn;
      const double dq = std::round(disp / m.disparity_step_px) * m.disparity_step_px;
      if (dq <= 0) continue;
      const double zq = bf / dq;
      if (zq < m.min_range || zq > m.max_range) continue;
      o[x] = static_cast<float>(zq);
    }
  }
  return out;
}

cv::Mat apply_color_camera(const cv::Mat& radiance, const ColorCameraModel& m, FrameRng& rng) {
  cv::Mat img;
  if (m.optics_sigma_px > 0)
    cv::GaussianBlur(radiance, img, cv::Size(3, 3), m.optics_sigma_px, m.optics_sigma_px, cv::BORDER_REPLICATE);
  else
    img = radiance;
  const int H = img.rows, W = img.cols;
  cv::Mat out(H, W, CV_8UC3);
  const float cx = (W - 1) / 2.f, cy = (H - 1) / 2.f;
  const float r2max = cx * cx + cy * cy;
  const float read_var = static_cast<float>(m.read_sigma * m.read_sigma), shot = static_cast<float>(m.shot_gain);
  for (int y = 0; y < H; ++y) {
    const float* in = img.ptr<float>(y);
    uint8_t* o = out.ptr<uint8_t>(y);
    for (int x = 0; x < W; ++x) {
      const float r2 = ((x - cx) * (x - cx) + (y - cy) * (y - cy)) / r2max;
      const float g = static_cast<float>(m.exposure) * (1.f - static_cast<float>(m.vignetting) * r2);
      float gn[4] = {0, 0, 0, 0};
      if (m.noise) rng.gaussian4(gn);
      for (int c = 0; c < 3; ++c) {
        float v = in[3 * x + c] * g;
        if (m.noise) v += gn[c] * std::sqrt(read_var + shot * std::max(v, 0.f));
        v *= static_cast<float>(m.gain);
        o[3 * x + c] = static_cast<uint8_t>(std::clamp(std::lround(v), 0L, 255L));
      }
    }
  }
  return out;
}

cv::Mat depth_to_u16(const cv::Mat& depth_m, double factor) {
  cv::Mat out(depth_m.rows, depth_m.cols, CV_16U);
  for (int y = 0; y < depth_m.rows; ++y) {
    const float* d = depth_m.ptr<float>(y);
    uint16_t* o = out.ptr<uint16_t>(y);
    for (int x = 0; x < depth_m.cols; ++x) {
      const double v = std::round(d[x] * factor);
      o[x] = (d[x] > 0 && v <= 65535.0) ? static_cast<uint16_t>(v) : 0;
    }
  }
  return out;
}

}  // namespace builtscene::synth
