// The pipeline's upright patches and decoder search levels, against symbols turned by a known
// angle (closed-form truth: the rendered text and the rotation applied).
#include <gtest/gtest.h>

#include "barcode/decoder.hpp"
#include "barcode/direction_estimator.hpp"
#include "barcode/scan_pipeline.hpp"
#include "test_images.hpp"

namespace builtscene::barcode {
namespace {

// The region the detector would report for a symbol turned by `angle` at the canvas centre.
Region region_for(const cv::Mat& symbol, double angle, cv::Size canvas) {
  Region r;
  r.box = cv::RotatedRect(cv::Point2f(canvas.width / 2.0f, canvas.height / 2.0f),
                          cv::Size2f(static_cast<float>(symbol.cols), static_cast<float>(symbol.rows)),
                          static_cast<float>(angle));
  return r;
}

TEST(UprightRegion, PatchOfATurnedRegionReadsWithTheTrueAndTheEstimatedAngle) {
  const ZXingDecoder quick(ZXingSearch::quick), upright(ZXingSearch::quick, 3);
  const cv::Size canvas(900, 700);
  int missed_as_is = 0;
  for (double angle : {30.0, 45.0, -40.0, 60.0, 90.0}) {
    const std::string text = "RM16" + std::to_string(10 + static_cast<int>(std::abs(angle))) + "C";
    const cv::Mat symbol = synth::render_barcode(text, "Code128", 3, 22);
    const cv::Mat image = test::rotated_on_canvas(symbol, angle, canvas, 225);
    const Region region = region_for(symbol, angle, canvas);
    if (quick.decode(image, 1).empty()) ++missed_as_is;

    const cv::Mat patch = upright_region(image, region, angle);
    EXPECT_GT(patch.cols, patch.rows) << "scan direction runs along x, angle " << angle;
    const auto with_truth = upright.decode(patch, 1);
    ASSERT_EQ(with_truth.size(), 1u) << "true angle " << angle;
    EXPECT_EQ(with_truth[0].text, text);

    const auto est = DirectionEstimator().scan_angle(image(region.bounds(image.size())));
    ASSERT_TRUE(est.has_value()) << angle;
    EXPECT_LT(test::angle_error(*est, angle), 5.0) << angle;
    const auto with_estimate = upright.decode(upright_region(image, region, *est), 1);
    ASSERT_EQ(with_estimate.size(), 1u) << "estimated angle " << *est << " for " << angle;
    EXPECT_EQ(with_estimate[0].text, text);
  }
  EXPECT_GE(missed_as_is, 3) << "the quick decoder read the turned symbols as they are; the test shows nothing";
}

// The pipeline's whole-frame pass keeps zxing's 90-degree retry: a symbol turned by 90 degrees
// is read by the `rotated` search and missed by the `quick` one (rows only).
TEST(ZXingSearch, RotatedSearchReadsSymbolsTurnedByNinetyDegrees) {
  const std::string text = "RM1602A";
  const cv::Mat symbol = synth::render_barcode(text, "Code128", 3, 22);
  const cv::Mat image = test::rotated_on_canvas(symbol, 90.0, cv::Size(640, 640), 230);
  EXPECT_TRUE(ZXingDecoder(ZXingSearch::quick).decode(image, 1).empty());
  const auto rotated = ZXingDecoder(ZXingSearch::rotated).decode(image, 1);
  ASSERT_EQ(rotated.size(), 1u);
  EXPECT_EQ(rotated[0].text, text);
  const auto upright = ZXingDecoder(ZXingSearch::quick).decode(test::rotated_on_canvas(symbol, 0.0, {640, 640}, 230), 1);
  ASSERT_EQ(upright.size(), 1u);
  EXPECT_EQ(upright[0].text, text);
}

}  // namespace
}  // namespace builtscene::barcode
