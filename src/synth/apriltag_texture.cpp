#include "synth/apriltag_texture.hpp"

#include <memory>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

extern "C" {
#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>
}

namespace builtscene::synth {
namespace {
struct FamilyDeleter {
  void operator()(apriltag_family_t* f) const { tag36h11_destroy(f); }
};
const apriltag_family_t& family() {
  static std::unique_ptr<apriltag_family_t, FamilyDeleter> fam(tag36h11_create());
  return *fam;
}
}  // namespace

int tag36h11_code_count() { return static_cast<int>(family().ncodes); }

cv::Mat tag36h11_image(int id, int cell_px) {
  const apriltag_family_t& f = family();
  if (id < 0 || id >= static_cast<int>(f.ncodes)) throw std::out_of_range("tag36h11 id " + std::to_string(id));
  const int total = f.total_width;            // 10 for tag36h11 (white border included)
  const int border = f.width_at_border;       // 8: the black square
  const int start = (total - border) / 2;     // first black cell
  cv::Mat cells(total, total, CV_8U, cv::Scalar(255));
  // Black square (the data cells are drawn white on it below).
  cells(cv::Rect(start, start, border, border)).setTo(0);
  // Bits: MSB first; bit_x/bit_y count cells from the black square's outer corner.
  const uint64_t code = f.codes[id];
  for (uint32_t i = 0; i < f.nbits; ++i) {
    const bool white = (code >> (f.nbits - 1 - i)) & 1u;
    if (white) cells.at<uint8_t>(static_cast<int>(f.bit_y[i]) + start, static_cast<int>(f.bit_x[i]) + start) = 255;
  }
  cv::Mat big;
  cv::resize(cells, big, cv::Size(total * cell_px, total * cell_px), 0, 0, cv::INTER_NEAREST);
  cv::Mat bgr;
  cv::cvtColor(big, bgr, cv::COLOR_GRAY2BGR);
  return bgr;
}

}  // namespace builtscene::synth
