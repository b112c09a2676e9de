#include "barcode/decoder.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>
#include <ZXing/ReadBarcode.h>

namespace builtscene::barcode {

using detail::as_gray_continuous;
using detail::same_symbol;
using detail::sort_by_position;

namespace {

// Paints over a found symbol so that the next single-symbol search finds another one. The
// quadrilateral of a 1D result spans the scan lines that read it; it is widened across the bars
// (the symbol is taller than the lines that read it) and a little along them.
void paint_over(cv::Mat& gray, const DecodedSymbol& s, float grow) {
  const cv::Point2f c = (s.corners[0] + s.corners[1] + s.corners[2] + s.corners[3]) * 0.25f;
  cv::Point2f along = (s.corners[1] - s.corners[0]) + (s.corners[2] - s.corners[3]);
  float len = std::hypot(along.x, along.y) * 0.5f;
  if (len < 1.0f) {
    along = {1.0f, 0.0f};
    len = 1.0f;
  }
  const cv::Point2f u = along * (1.0f / (std::hypot(along.x, along.y)));
  const cv::Point2f n(-u.y, u.x);
  const float half_len = len * 0.5f * 1.12f + 6.0f;
  const float half_h = std::max(len * 0.35f, 14.0f) * grow;
  std::vector<cv::Point> poly;
  for (const auto& [a, b] : {std::pair{-1.f, -1.f}, {1.f, -1.f}, {1.f, 1.f}, {-1.f, 1.f}}) {
    const cv::Point2f p = c + u * (a * half_len) + n * (b * half_h);
    poly.emplace_back(cvRound(p.x), cvRound(p.y));
  }
  cv::fillConvexPoly(gray, poly, cv::Scalar(255));
}

DecodedSymbol from_zxing(const ZXing::Result& r) {
  DecodedSymbol s;
  s.text = r.text();
  s.symbology = ZXing::ToString(r.format());
  const auto& p = r.position();
  for (int i = 0; i < 4; ++i) s.corners[static_cast<std::size_t>(i)] = cv::Point2f(static_cast<float>(p[i].x), static_cast<float>(p[i].y));
  return s;
}

}  // namespace

std::vector<DecodedSymbol> ZXingDecoder::decode(const cv::Mat& image, int max_symbols) const {
  std::vector<DecodedSymbol> found;
  if (image.empty()) return found;
  cv::Mat gray = as_gray_continuous(image);
  ZXing::DecodeHints hints;
  // The 1D symbologies of labels; GS1 DataBar (coupons, fresh food) is left out: its readers
  // cost as much as all the others together.
  using F = ZXing::BarcodeFormat;
  hints.setFormats(F::Codabar | F::Code39 | F::Code93 | F::Code128 | F::EAN8 | F::EAN13 | F::ITF | F::UPCA | F::UPCE);
  hints.setTryHarder(true);
  hints.setTryRotate(search_ != ZXingSearch::quick);
  hints.setTryDownscale(search_ == ZXingSearch::thorough);
  hints.setMinLineCount(static_cast<uint8_t>(std::clamp(min_lines_, 1, 16)));
  // The one setting that keeps zxing-cpp 1.4 away from its multi-symbol assertion (see header).
  hints.setMaxNumberOfSymbols(1);
  bool painted = false;
  float grow = 1.0f;
  // Each round either finds a new symbol or grows the mask over a repeat, so this terminates.
  for (int round = 0; round < max_symbols + 6 && static_cast<int>(found.size()) < max_symbols; ++round) {
    const ZXing::ImageView view(gray.data, gray.cols, gray.rows, ZXing::ImageFormat::Lum,
                                static_cast<int>(gray.step[0]));
    const ZXing::Result r = ZXing::ReadBarcode(view, hints);
    if (!r.isValid()) break;
    DecodedSymbol s = from_zxing(r);
    const bool rejected = !detail::plausible(s);
    const bool repeat =
        rejected || std::any_of(found.begin(), found.end(), [&](const DecodedSymbol& f) { return same_symbol(f, s); });
    if (max_symbols == 1 && !repeat) {
      found.push_back(std::move(s));
      break;
    }
    if (!painted) {
      gray = gray.clone();  // never write into the caller's image
      painted = true;
    }
    if (rejected) {
      grow = 1.0f;
    } else if (repeat) {
      grow *= 1.8f;
    } else {
      grow = 1.0f;
      found.push_back(s);
    }
    paint_over(gray, s, grow);
  }
  sort_by_position(found);
  return found;
}

}  // namespace builtscene::barcode
