#include "barcode/direction_estimator.hpp"

#include <gtest/gtest.h>

#include "barcode/decoder.hpp"
#include "test_images.hpp"

namespace builtscene::barcode {
namespace {

// Closed form: a symbol turned by a known angle; the estimate must equal that angle.
class KnownAngle : public ::testing::TestWithParam<double> {};

TEST_P(KnownAngle, EstimatesTheScanDirectionOfARotatedBarcode) {
  const double angle = GetParam();
  const cv::Mat symbol = synth::render_barcode("RM1401A", "Code128", 3, 30);
  const cv::Mat image = test::rotated_on_canvas(symbol, angle, cv::Size(520, 520), 200);
  const auto est = DirectionEstimator().scan_angle(image);
  ASSERT_TRUE(est.has_value());
  EXPECT_LT(test::angle_error(*est, angle), 3.0) << "true " << angle << " estimated " << *est;
}

INSTANTIATE_TEST_SUITE_P(Angles, KnownAngle, ::testing::Values(0.0, 10.0, 30.0, 45.0, 60.0, 90.0, 120.0, 135.0, 165.0));

TEST(DirectionEstimator, UprightMakesTheScanDirectionHorizontal) {
  const cv::Mat symbol = synth::render_barcode("RM1602C", "Code128", 3, 30);
  const cv::Mat image = test::rotated_on_canvas(symbol, 37.0, cv::Size(520, 520), 200);
  const cv::Mat up = DirectionEstimator::upright(image, 37.0);
  const auto est = DirectionEstimator().scan_angle(up);
  ASSERT_TRUE(est.has_value());
  EXPECT_LT(test::angle_error(*est, 0.0), 3.0);
}

TEST(DirectionEstimator, FlatImageHasNoDirection) {
  const cv::Mat flat(200, 300, CV_8UC1, cv::Scalar(128));
  EXPECT_FALSE(DirectionEstimator().scan_angle(flat).has_value());
  EXPECT_FALSE(DirectionEstimator().scan_angle(cv::Mat()).has_value());
}

// Acceptance (rotation): labels rolled 30-45 degrees that the decoder alone misses are read
// after direction estimation and rotation.
TEST(DirectionEstimator, RotationRecoversLabelsTheDecoderAloneMisses) {
  const ZXingDecoder decoder;
  int missed_alone = 0, read_after = 0;
  for (double angle : {30.0, 35.0, 40.0, 45.0, -30.0, -45.0}) {
    const std::string text = "RM15" + std::to_string(10 + static_cast<int>(std::abs(angle))) + "B";
    const cv::Mat symbol = synth::render_barcode(text, "Code128", 3, 22);
    const cv::Mat image = test::rotated_on_canvas(symbol, angle, cv::Size(640, 480), 230);
    const auto alone = decoder.decode(image, 4);
    const bool alone_ok = !alone.empty() && alone[0].text == text;
    if (!alone_ok) ++missed_alone;
    const auto est = DirectionEstimator().scan_angle(image);
    ASSERT_TRUE(est.has_value()) << angle;
    const auto after = decoder.decode(DirectionEstimator::upright(image, *est), 1);
    ASSERT_EQ(after.size(), 1u) << "angle " << angle;
    EXPECT_EQ(after[0].text, text);
    ++read_after;
  }
  EXPECT_GT(missed_alone, 0) << "the decoder alone read every rotated label; the test shows nothing";
  EXPECT_EQ(read_after, 6);
}

}  // namespace
}  // namespace builtscene::barcode
