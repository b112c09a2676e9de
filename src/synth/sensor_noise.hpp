#pragma once
// What the sensor does to a perfect render: Kinect-like depth noise and colour-camera
// effects (optics blur, exposure, vignetting, shot and read noise, 8-bit quantization).
#include <cstdint>

#include <opencv2/core.hpp>

namespace builtscene::synth {

// Deterministic per-frame random numbers (splitmix64 + a fixed Gaussian table).
class FrameRng {
 public:
  FrameRng(std::uint64_t seed, std::uint64_t frame, std::uint64_t stream);
  std::uint64_t next() {
    std::uint64_t z = (s_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  float uniform() { return static_cast<float>(next() >> 40) * (1.0f / 16777216.0f); }
  float gaussian();  // N(0, 1), smooth
  // Four N(0, 1) values from one draw (65536 quantiles; coarser in the far tails).
  void gaussian4(float* out);

 private:
  std::uint64_t s_;
};

struct KinectNoiseModel {
  double min_range = 0.5, max_range = 8.0;
  double baseline_m = 0.075, focal_px = 580.0;  // IR projector-camera pair (disparity units)
  double disparity_step_px = 1.0 / 8.0;         // sub-pixel quantization of disparity
  double lateral_sigma_px = 0.5;
  double grazing_cos = 0.22;                    // no reading below this |cos| (about 77 degrees)
  double grazing_soft_cos = 0.35;               // readings thin out between the two
  double edge_jump = 0.04;                      // relative depth step counted as a discontinuity
  double dropout = 0.002;                       // random missing pixels

  // Axial standard deviation (m) at depth z: 0.0012 + 0.0019 (z - 0.4)^2.
  static double axial_sigma(double z) { return 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4); }
};

// True depth (CV_32F metres, 0 = none) and incidence |cos| -> Kinect-like depth (CV_32F).
cv::Mat apply_kinect_noise(const cv::Mat& depth, const cv::Mat& incidence, const KinectNoiseModel& model, FrameRng& rng);

struct ColorCameraModel {
  double exposure = 1.0;        // gain applied to the render's radiance
  double gain = 1.0;            // amplifier gain after the sensor's noise (auto-gain in the dark)
  bool noise = true;            // shot + read noise
  double read_sigma = 1.6;      // 8-bit units
  double shot_gain = 0.12;      // variance per unit of signal
  double vignetting = 0.25;     // relative fall-off at the corners
  double optics_sigma_px = 0.6; // lens blur
};

// Float radiance (CV_32FC3) -> 8-bit BGR image as the camera would record it.
cv::Mat apply_color_camera(const cv::Mat& radiance, const ColorCameraModel& model, FrameRng& rng);

// 16-bit PNG depth: round(z * factor), 0 for no reading or beyond 65535.
cv::Mat depth_to_u16(const cv::Mat& depth_m, double factor = 5000.0);

}  // namespace builtscene::synth
