#pragma once
// Decoders for 1D symbols: zxing-cpp (default), ZBar, or both. A tiny interface over the two
// libraries so the pipeline can decode a whole frame, a region crop or an uprighted crop alike.
#include <array>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace builtscene::barcode {

// One decoded symbol. `symbology` uses zxing-cpp's names ("Code128", "EAN-13", "Code39", ...)
// for both decoders so inventories from either compare equal.
struct DecodedSymbol {
  std::string text;
  std::string symbology;
  std::array<cv::Point2f, 4> corners{};  // in the pixel frame of the image given to decode()
};

enum class DecoderKind { zxing, zbar, both };

DecoderKind parse_decoder_kind(const std::string& name);  // throws InputError on unknown names
std::string to_string(DecoderKind kind);

// Decodes 1D symbols from an 8-bit gray image. ITF with fewer than 10 digits is not reported
// (short ITF is the usual false read: pieces of other symbols, repetitive structures). Implementations are stateless and may be called
// from several threads at once.
class Decoder {
 public:
  virtual ~Decoder() = default;
  // At most `max_symbols` distinct symbols (>= 1), sorted by position (top-left first).
  virtual std::vector<DecodedSymbol> decode(const cv::Mat& gray, int max_symbols) const = 0;
  virtual std::string name() const = 0;
};

// How hard zxing-cpp searches an image. quick: rows only (tryHarder: every few rows);
// rotated: rows, then columns (its 90-degree retry); thorough: also a downscaled pyramid
// (zxing-cpp's defaults, the decoder alone).
enum class ZXingSearch { quick, rotated, thorough };

// zxing-cpp 1.4 aborts the process on an internal assertion (Result::operator==, lineCount() == 1)
// when one ReadBarcodes call gathers several 1D symbols and then compares a symbol that already
// has two scan lines. This decoder never asks zxing for more than one symbol per call: a search
// for a single symbol stops as soon as its first symbol reaches two lines, before any such
// comparison can happen. Several symbols are read by repeating the call with every symbol found
// so far painted over.
class ZXingDecoder final : public Decoder {
 public:
  // quick: for crops that the pipeline has already cut out and turns upright itself.
  // min_lines: scan lines that must agree on a symbol (zxing's default is 2). Uprighted region
  // patches use 3: resampled bars of a weak symbology (Code 39 has no check character) can
  // otherwise give one-off misreads, e.g. "/650831" for P650831 on the generated 2000-frame scan.
  explicit ZXingDecoder(ZXingSearch search = ZXingSearch::thorough, int min_lines = 2)
      : search_(search), min_lines_(min_lines) {}
  std::vector<DecodedSymbol> decode(const cv::Mat& gray, int max_symbols) const override;
  std::string name() const override { return "zxing"; }

 private:
  ZXingSearch search_;
  int min_lines_;
};

class ZBarDecoder final : public Decoder {
 public:
  std::vector<DecodedSymbol> decode(const cv::Mat& gray, int max_symbols) const override;
  std::string name() const override { return "zbar"; }
};

// zxing first; ZBar for whatever zxing did not read.
class CombinedDecoder final : public Decoder {
 public:
  explicit CombinedDecoder(ZXingSearch search = ZXingSearch::thorough, int min_lines = 2) : zxing_(search, min_lines) {}
  std::vector<DecodedSymbol> decode(const cv::Mat& gray, int max_symbols) const override;
  std::string name() const override { return "both"; }

 private:
  ZXingDecoder zxing_;
  ZBarDecoder zbar_;
};

// search, min_lines: see ZXingDecoder (ZBar has no such settings).
std::unique_ptr<Decoder> make_decoder(DecoderKind kind, ZXingSearch search = ZXingSearch::thorough, int min_lines = 2);

namespace detail {
cv::Mat as_gray_continuous(const cv::Mat& image);
void sort_by_position(std::vector<DecodedSymbol>& symbols);
bool same_symbol(const DecodedSymbol& a, const DecodedSymbol& b);
// False-read guard shared by the decoders: ITF shorter than 10 digits is rejected.
bool plausible(const DecodedSymbol& s);
}  // namespace detail

}  // namespace builtscene::barcode
