#include "barcode/region_detector.hpp"

#include <gtest/gtest.h>

#include "test_images.hpp"

namespace builtscene::barcode {
namespace {

// Labels pasted at known places on a mid-gray background with clutter: every label centre must
// fall inside a detected region, and no region may lie on the clutter alone.
TEST(RegionDetector, FindsEveryLabelAndNothingElse) {
  cv::Mat frame(540, 960, CV_8UC1, cv::Scalar(110));
  // Clutter: dark stripes (few children), a plain bright rectangle (no children).
  for (int k = 0; k < 4; ++k) cv::rectangle(frame, cv::Rect(60 + 12 * k, 400, 6, 60), cv::Scalar(30), cv::FILLED);
  cv::rectangle(frame, cv::Rect(700, 420, 180, 80), cv::Scalar(240), cv::FILLED);
  const std::vector<std::pair<std::string, cv::Point>> labels = {
      {"RM1401A", {220, 120}}, {"RM1402B", {640, 140}}, {"RM1601C", {420, 330}}};
  for (const auto& [text, centre] : labels) {
    cv::Mat sym = synth::render_barcode(text, "Code128", 2, 25);
    cv::copyMakeBorder(sym, sym, 8, 8, 8, 8, cv::BORDER_CONSTANT, cv::Scalar(255));
    sym.copyTo(frame(cv::Rect(centre.x - sym.cols / 2, centre.y - sym.rows / 2, sym.cols, sym.rows)));
  }
  RegionOptions o;
  o.threshold = 0.6;
  const auto regions = RegionDetector(o).detect(frame);
  for (const auto& [text, centre] : labels) {
    bool found = false;
    for (const auto& r : regions) found = found || r.bounds(frame.size()).contains(centre);
    EXPECT_TRUE(found) << text;
  }
  for (const auto& r : regions) {
    bool on_label = false;
    for (const auto& [text, centre] : labels) on_label = on_label || r.bounds(frame.size()).contains(centre);
    EXPECT_TRUE(on_label) << "region at " << r.box.center << " covers no label";
  }
}

TEST(RegionDetector, RotatedLabelGivesARotatedBox) {
  const cv::Mat sym = synth::render_barcode("RM1502A", "Code128", 3, 22);
  const cv::Mat frame = test::rotated_on_canvas(sym, 40.0, cv::Size(800, 600), 100);
  RegionOptions o;
  o.threshold = 0.6;
  o.scale = 1.0;
  const auto regions = RegionDetector(o).detect(frame);
  ASSERT_FALSE(regions.empty());
  // The box's long side lies along the scan direction (40 degrees), within a few degrees.
  const auto& b = regions.front().box;
  double long_angle = b.size.width >= b.size.height ? b.angle : b.angle + 90.0;
  EXPECT_LT(test::angle_error(long_angle, 40.0), 4.0) << "box angle " << b.angle << " size " << b.size;
}

TEST(RegionDetector, EmptyAndFlatFramesGiveNoRegions) {
  EXPECT_TRUE(RegionDetector().detect(cv::Mat()).empty());
  EXPECT_TRUE(RegionDetector().detect(cv::Mat(300, 400, CV_8UC3, cv::Scalar::all(200))).empty());
}

}  // namespace
}  // namespace builtscene::barcode
