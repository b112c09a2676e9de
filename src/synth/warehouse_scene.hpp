#pragma once
// A generated warehouse scan: a facade of storage racks (uprights, beams, boxes) with location
// labels on the beams (Code 128, RM1401A ... RM1602C) and smaller product labels on boxes
// (EAN-13, Code 39, Code 128), all rendered with libzint, filmed by a handheld or drone camera
// that sweeps along the racks with left-right shake, speed changes and revisits, roll up to
// +-45 degrees, perspective, motion blur, defocus, uneven light and shadows across labels.
//
// Ground truth by construction: for every label and frame, whether it is visible and whether
// it is legible (whole symbol in view, module at least 1.5 px, blur across the bars and defocus
// small against the module, enough light on it).
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace builtscene::synth {

struct WarehouseOptions {
  std::uint64_t seed = 1;
  int frames = 2000;
  cv::Size size{1920, 1080};
  int location_labels = 18;  // 6 per rack bay (2 columns x 3 levels); a multiple of 6, 6..36
  bool product_labels = true;
  std::string format = "avi";  // "avi" (MJPG) or "png" (numbered frames in DIR/frames/)
  int threads = 2;
};

struct WarehouseLabel {
  std::string text;
  std::string symbology;  // zxing-cpp names: Code128, Code39, EAN-13
  std::string kind;       // "location" or "product"
  cv::Rect2f bars;        // the bar area in world pixels (quiet zones included)
  int modules = 0;        // module count across the symbol
  float module_world = 0; // world pixels per module
};

// Per-frame camera state (world -> frame homography and the image degradations).
struct WarehouseCamera {
  cv::Matx33d H;               // world -> frame
  double x = 0, y = 0;         // world point at the frame centre
  double scale = 1, roll_deg = 0;
  cv::Point2d blur;            // motion blur vector in frame pixels (the path during exposure)
  double defocus = 0;          // Gaussian sigma in frame pixels (0: sharp)
  double light = 1;            // global exposure factor
  cv::Point2d light_gradient;  // exposure change per frame pixel from the centre (x, y)
};

class WarehouseScene {
 public:
  explicit WarehouseScene(const WarehouseOptions& options);  // throws InputError on bad options

  const std::vector<WarehouseLabel>& labels() const { return labels_; }
  const std::vector<WarehouseCamera>& cameras() const { return cameras_; }
  const cv::Mat& world() const { return world_; }

  // Frame i (BGR), deterministic for (seed, i), independent of other frames.
  cv::Mat render(int i) const;

  // Visibility and legibility of label l in frame i, from the construction.
  bool visible(std::size_t l, int i) const;
  bool legible(std::size_t l, int i) const;

 private:
  void build_world(std::uint64_t seed);
  void build_path(std::uint64_t seed);
  double light_at_world(const cv::Point2f& p) const;

  WarehouseOptions options_;
  std::vector<WarehouseLabel> labels_;
  std::vector<WarehouseCamera> cameras_;
  cv::Mat world_;        // BGR albedo x baked shadows
  cv::Mat world_light_;  // CV_32F, quarter resolution: baked light factor (shadows)
  cv::Rect2d content_;   // world area holding racks
};

// A 1D symbol rendered by libzint as an 8-bit gray image (black bars on white, quiet zones and
// human-readable text included). symbology: "Code128", "Code39" or "EAN-13" (12 or 13 digits);
// module: pixels per module (a multiple of 1). Throws InputError for other names or bad text.
cv::Mat render_barcode(const std::string& text, const std::string& symbology, int module = 2, int height_modules = 30);

// Renders the scan to DIR: scan.avi (or frames/NNNNNN.png), truth.csv, camera.csv.
// Returns a summary: frames, labels, legible labels, seconds, files.
struct WarehouseWriteResult {
  std::filesystem::path video;
  std::filesystem::path truth;
  int frames = 0;
  int labels = 0;
  int location_labels = 0;
  int legible_labels = 0;
  double seconds = 0;
};
WarehouseWriteResult write_warehouse_scan(const std::filesystem::path& dir, const WarehouseOptions& options);

}  // namespace builtscene::synth
