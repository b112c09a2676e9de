#include "barcode/decoder.hpp"

#include <ZXing/ReadBarcode.h>
#include <ZXing/ZXVersion.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "core/errors.hpp"
#include "test_images.hpp"

namespace builtscene::barcode {
namespace {

// Nine 1D symbols (Code 128 and Code 39) in a grid, three texts appearing twice (the same product
// on several boxes): the kind of image on which zxing-cpp 1.4's ReadBarcodes (several symbols)
// aborts on `lineCount() == 1` in Result::operator==. `truth` gets the six distinct codes.
cv::Mat several_symbols(std::vector<std::pair<std::string, std::string>>& truth) {
  cv::Mat img(700, 1000, CV_8UC1, cv::Scalar(255));
  for (int k = 0; k < 9; ++k) {
    const int t = k % 6;
    const std::string sym = t % 3 == 1 ? "Code39" : "Code128";
    const std::string text = (t % 3 == 1 ? "LOC" : "RM") + std::to_string(1400 + 7 * t) + (t % 3 == 1 ? "" : "A");
    const cv::Mat b = synth::render_barcode(text, sym, 2, 40);
    const int x = 20 + (k % 3) * 320, y = 20 + (k / 3) * 220;
    if (x + b.cols > img.cols || y + b.rows > img.rows) continue;
    b.copyTo(img(cv::Rect(x, y, b.cols, b.rows)));
    if (std::find(truth.begin(), truth.end(), std::pair{text, sym}) == truth.end()) truth.emplace_back(text, sym);
  }
  return img;
}

TEST(ZXingDecoder, SeveralOneDSymbolsInOneImageNeitherAbortNorGetLost) {
  std::vector<std::pair<std::string, std::string>> truth;
  const cv::Mat img = several_symbols(truth);
  ASSERT_GE(truth.size(), 6u);
  const auto found = ZXingDecoder().decode(img, 32);  // would abort the process if unguarded
  std::set<std::pair<std::string, std::string>> got;
  for (const auto& s : found) got.insert({s.text, s.symbology});
  for (const auto& t : truth) EXPECT_TRUE(got.count(t)) << t.second << " " << t.first;
  EXPECT_EQ(got.size(), truth.size()) << "false or duplicate codes";
}

// The same image really is the fault case: zxing-cpp 1.4's own multi-symbol call dies on it.
TEST(ZXingDecoderDeathTest, TheLibraryItselfAbortsOnThisImage) {
#if ZXING_VERSION_MAJOR == 1 && ZXING_VERSION_MINOR == 4
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  std::vector<std::pair<std::string, std::string>> truth;
  const cv::Mat img = several_symbols(truth);
  EXPECT_DEATH(
      {
        ZXing::DecodeHints hints;
        (void)ZXing::ReadBarcodes(ZXing::ImageView(img.data, img.cols, img.rows, ZXing::ImageFormat::Lum), hints);
      },
      "lineCount");
#else
  GTEST_SKIP() << "the abort is specific to zxing-cpp 1.4";
#endif
}

TEST(ZBarDecoder, ReadsTheSameSymbols) {
  std::vector<std::pair<std::string, std::string>> truth;
  const cv::Mat img = several_symbols(truth);
  const auto found = ZBarDecoder().decode(img, 32);
  std::set<std::pair<std::string, std::string>> got;
  for (const auto& s : found) got.insert({s.text, s.symbology});
  for (const auto& t : truth) EXPECT_TRUE(got.count(t)) << t.second << " " << t.first;
}

TEST(Decoders, Ean13AndCombined) {
  const cv::Mat b = synth::render_barcode("4006381333931", "EAN-13", 2, 40);
  cv::Mat img(b.rows + 40, b.cols + 40, CV_8UC1, cv::Scalar(255));
  b.copyTo(img(cv::Rect(20, 20, b.cols, b.rows)));
  for (auto kind : {DecoderKind::zxing, DecoderKind::zbar, DecoderKind::both}) {
    const auto found = make_decoder(kind)->decode(img, 4);
    ASSERT_EQ(found.size(), 1u) << to_string(kind);
    EXPECT_EQ(found[0].text, "4006381333931");
    EXPECT_EQ(found[0].symbology, "EAN-13");
  }
}

TEST(Decoders, NothingInNoiseAndBadNames) {
  cv::Mat noise(300, 400, CV_8UC1);
  cv::RNG(7).fill(noise, cv::RNG::UNIFORM, 0, 256);
  EXPECT_TRUE(ZXingDecoder().decode(noise, 8).empty());
  EXPECT_TRUE(ZBarDecoder().decode(noise, 8).empty());
  EXPECT_TRUE(ZXingDecoder().decode(cv::Mat(), 8).empty());
  EXPECT_THROW(parse_decoder_kind("clearimage"), InputError);
}

}  // namespace
}  // namespace builtscene::barcode

namespace builtscene::barcode {
namespace {

TEST(Decoders, ShortItfIsRejectedAsAFalseRead) {
  EXPECT_FALSE(detail::plausible({"603726", "ITF", {}}));  // a piece of a Code 128 label, read as ITF
  EXPECT_TRUE(detail::plausible({"10012345000017", "ITF", {}}));
  EXPECT_TRUE(detail::plausible({"603726", "Code128", {}}));
}

}  // namespace
}  // namespace builtscene::barcode
