#include "synth/sensor_noise.hpp"

#include <array>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace builtscene::synth {
namespace {

// Gaussian values by the inverse CDF on a regular grid of quantiles: fixed, so identical on
// every platform (std::normal_distribution is implementation-defined).
const std::array<float, 4096>& gaussian_table() {
  static const std::array<float, 4096> table = [] {
    std::array<float, 4096> t{};
    for (int i = 0; i < 4096; ++i) {
      const double p = (i + 0.5) / 4096.0;
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
  const auto& t = gaussian_table();
  const std::size_t i = static_cast<std::size_t>(r & 4095u);
  const float j = static_cast<float>((r >> 12) & 0xFFFF) / 65536.0f;
  const float lo = t[i], hi = i + 1 < 4096 ? t[i + 1] : t[i];
  return lo + (hi - lo) * j;
}

cv::Mat apply_kinect_noise(const cv::Mat& depth, const cv::Mat& incidence, const KinectNoiseModel& m, FrameRng& rng) {
  const int H = depth.rows, W = depth.cols;
  cv::Mat out(H, W, CV_32F, cv::Scalar(0));
  const double bf = m.baseline_m * m.focal_px;
  const int max_shift = 2;
  for (int y = 0; y < H; ++y) {
    const float* inc = incidence.ptr<float>(y);
    float* o = out.ptr<float>(y);
    for (int x = 0; x < W; ++x) {
      // Lateral noise: the reading comes from a slightly displaced point of the surface.
      const int sx = std::clamp(x + static_cast<int>(std::lround(rng.gaussian() * m.lateral_sigma_px)), 0, W - 1);
      const int sy = std::clamp(y + static_cast<int>(std::lround(rng.gaussian() * m.lateral_sigma_px)), 0, H - 1);
      const float z = depth.at<float>(sy, sx);
      if (z <= 0.f || z < m.min_range || z > m.max_range) continue;
      // Discontinuities: the block matcher fails next to a depth step.
      bool edge = false;
      for (int dy = -1; dy <= 1 && !edge; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = std::clamp(x + dx, 0, W - 1), yy = std::clamp(y + dy, 0, H - 1);
          const float zn = depth.at<float>(yy, xx);
          if (zn <= 0.f || std::abs(zn - z) > m.edge_jump * z) {
            edge = true;
            break;
          }
        }
      if (edge) continue;
      // Projector shadow: a nearer surface up to a few pixels to the right hides the pattern.
      bool shadow = false;
      for (int k = 1; k <= 12 && x + k < W; ++k) {
        const float zn = depth.at<float>(y, x + k);
        if (zn > 0.f && zn < z * (1.f - static_cast<float>(m.edge_jump)) && k < bf * (1.0 / zn - 1.0 / z) * 0.6 + max_shift) {
          shadow = true;
          break;
        }
      }
      if (shadow) continue;
      const float c = inc[x];
      if (c < m.grazing_cos) continue;
      if (c < m.grazing_soft_cos && rng.uniform() > (c - m.grazing_cos) / (m.grazing_soft_cos - m.grazing_cos)) continue;
      if (rng.uniform() < m.dropout) continue;
      // Axial noise, then disparity quantization.
      const double zn = z + rng.gaussian() * KinectNoiseModel::axial_sigma(z);
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
  for (int y = 0; y < H; ++y) {
    const float* in = img.ptr<float>(y);
    uint8_t* o = out.ptr<uint8_t>(y);
    for (int x = 0; x < W; ++x) {
      const float r2 = ((x - cx) * (x - cx) + (y - cy) * (y - cy)) / r2max;
      const float g = static_cast<float>(m.exposure) * (1.f - static_cast<float>(m.vignetting) * r2);
      for (int c = 0; c < 3; ++c) {
        float v = in[3 * x + c] * g;
        if (m.noise) v += rng.gaussian() * std::sqrt(static_cast<float>(m.read_sigma * m.read_sigma) + static_cast<float>(m.shot_gain) * std::max(v, 0.f));
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
