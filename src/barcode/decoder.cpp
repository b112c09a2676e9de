#include "barcode/decoder.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "core/errors.hpp"

namespace builtscene::barcode {

DecoderKind parse_decoder_kind(const std::string& name) {
  if (name == "zxing") return DecoderKind::zxing;
  if (name == "zbar") return DecoderKind::zbar;
  if (name == "both") return DecoderKind::both;
  throw InputError("--decoder: unknown decoder '" + name + "' (expected zxing, zbar or both)");
}

std::string to_string(DecoderKind kind) {
  switch (kind) {
    case DecoderKind::zxing: return "zxing";
    case DecoderKind::zbar: return "zbar";
    case DecoderKind::both: return "both";
  }
  return "?";
}

namespace detail {

cv::Mat as_gray_continuous(const cv::Mat& image) {
  cv::Mat gray;
  if (image.channels() == 3) {
    cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
  } else {
    gray = image;
  }
  if (gray.depth() != CV_8U) gray.convertTo(gray, CV_8U);
  return gray;
}

void sort_by_position(std::vector<DecodedSymbol>& symbols) {
  std::stable_sort(symbols.begin(), symbols.end(), [](const DecodedSymbol& a, const DecodedSymbol& b) {
    const float ay = std::min({a.corners[0].y, a.corners[1].y, a.corners[2].y, a.corners[3].y});
    const float by = std::min({b.corners[0].y, b.corners[1].y, b.corners[2].y, b.corners[3].y});
    if (std::abs(ay - by) > 1.0f) return ay < by;
    const float ax = std::min({a.corners[0].x, a.corners[1].x, a.corners[2].x, a.corners[3].x});
    const float bx = std::min({b.corners[0].x, b.corners[1].x, b.corners[2].x, b.corners[3].x});
    if (ax != bx) return ax < bx;
    return a.text < b.text;
  });
}

bool plausible(const DecodedSymbol& s) {
  // Interleaved 2 of 5 has no start/stop characters worth the name: pieces of other symbols and
  // of repetitive structures (rack uprights) decode as short ITF. Carton codes (ITF-14) and most
  // ITF in use have 10 digits or more.
  if (s.symbology == "ITF") return s.text.size() >= 10;
  return !s.text.empty();
}

bool same_symbol(const DecodedSymbol& a, const DecodedSymbol& b) {
  return a.text == b.text && a.symbology == b.symbology;
}

}  // namespace detail

std::vector<DecodedSymbol> CombinedDecoder::decode(const cv::Mat& gray, int max_symbols) const {
  auto found = zxing_.decode(gray, max_symbols);
  if (static_cast<int>(found.size()) >= max_symbols) return found;
  for (auto& s : zbar_.decode(gray, max_symbols)) {
    if (!detail::plausible(s)) continue;
    if (static_cast<int>(found.size()) >= max_symbols) break;
    if (std::none_of(found.begin(), found.end(), [&](const DecodedSymbol& f) { return detail::same_symbol(f, s); }))
      found.push_back(std::move(s));
  }
  detail::sort_by_position(found);
  return found;
}

std::unique_ptr<Decoder> make_decoder(DecoderKind kind, ZXingSearch search, int min_lines) {
  switch (kind) {
    case DecoderKind::zxing: return std::make_unique<ZXingDecoder>(search, min_lines);
    case DecoderKind::zbar: return std::make_unique<ZBarDecoder>();
    case DecoderKind::both: return std::make_unique<CombinedDecoder>(search, min_lines);
  }
  return std::make_unique<ZXingDecoder>(search, min_lines);
}

}  // namespace builtscene::barcode
