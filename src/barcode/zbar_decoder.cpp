#include "barcode/decoder.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>
#include <zbar.h>

namespace builtscene::barcode {

using detail::as_gray_continuous;
using detail::same_symbol;
using detail::sort_by_position;
using namespace zbar;

namespace {

std::string zbar_symbology(zbar_symbol_type_t t) {
  switch (t) {
    case ZBAR_EAN8: return "EAN-8";
    case ZBAR_UPCE: return "UPC-E";
    case ZBAR_UPCA: return "UPC-A";
    case ZBAR_EAN13: return "EAN-13";
    case ZBAR_I25: return "ITF";
    case ZBAR_CODABAR: return "Codabar";
    case ZBAR_CODE39: return "Code39";
    case ZBAR_CODE93: return "Code93";
    case ZBAR_CODE128: return "Code128";
    default: return zbar_get_symbol_name(t);
  }
}

}  // namespace

std::vector<DecodedSymbol> ZBarDecoder::decode(const cv::Mat& image, int max_symbols) const {
  std::vector<DecodedSymbol> found;
  if (image.empty()) return found;
  cv::Mat gray = as_gray_continuous(image);
  if (!gray.isContinuous()) gray = gray.clone();
  // One scanner per call: ZBar scanners keep state and are not shareable between threads.
  zbar_image_scanner_t* scanner = zbar_image_scanner_create();
  zbar_image_scanner_set_config(scanner, ZBAR_NONE, ZBAR_CFG_ENABLE, 0);
  for (zbar_symbol_type_t t : {ZBAR_EAN8, ZBAR_UPCE, ZBAR_UPCA, ZBAR_EAN13, ZBAR_I25, ZBAR_CODABAR, ZBAR_CODE39,
                               ZBAR_CODE93, ZBAR_CODE128}) {
    zbar_image_scanner_set_config(scanner, t, ZBAR_CFG_ENABLE, 1);
  }
  zbar_image_t* img = zbar_image_create();
  zbar_image_set_format(img, zbar_fourcc('Y', '8', '0', '0'));
  zbar_image_set_size(img, static_cast<unsigned>(gray.cols), static_cast<unsigned>(gray.rows));
  zbar_image_set_data(img, gray.data, gray.total(), nullptr);
  if (zbar_scan_image(scanner, img) > 0) {
    for (const zbar_symbol_t* sym = zbar_image_first_symbol(img); sym; sym = zbar_symbol_next(sym)) {
      DecodedSymbol s;
      s.text = zbar_symbol_get_data(sym);
      s.symbology = zbar_symbology(zbar_symbol_get_type(sym));
      const unsigned n = zbar_symbol_get_loc_size(sym);
      if (n > 0) {
        float x0 = 1e9f, y0 = 1e9f, x1 = -1e9f, y1 = -1e9f;
        for (unsigned i = 0; i < n; ++i) {
          const float x = static_cast<float>(zbar_symbol_get_loc_x(sym, i));
          const float y = static_cast<float>(zbar_symbol_get_loc_y(sym, i));
          x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
        }
        s.corners = {cv::Point2f(x0, y0), cv::Point2f(x1, y0), cv::Point2f(x1, y1), cv::Point2f(x0, y1)};
      }
      if (detail::plausible(s) &&
          std::none_of(found.begin(), found.end(), [&](const DecodedSymbol& f) { return same_symbol(f, s); }))
        found.push_back(std::move(s));
    }
  }
  zbar_image_destroy(img);
  zbar_image_scanner_destroy(scanner);
  sort_by_position(found);
  if (static_cast<int>(found.size()) > max_symbols) found.resize(static_cast<std::size_t>(std::max(0, max_symbols)));
  return found;
}

}  // namespace builtscene::barcode
