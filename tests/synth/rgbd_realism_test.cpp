// Realism check (issue 3): ORB features per frame and the fraction of pixels with valid depth
// on a generated lab-room sequence against the real 7-Scenes kitchen; the same order of
// magnitude is required (a factor of 3 either way), and the numbers are printed for the note.
#include <gtest/gtest.h>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "io/tum_dataset.hpp"
#include "rgbd_test_util.hpp"
#include "synth/rgbd_sequence_writer.hpp"

namespace bs = builtscene;
namespace synth = builtscene::synth;

namespace {

struct Stats {
  double features = 0, valid = 0, texture_fraction = 0, fast20 = 0;
};

Stats measure(const bs::TumDataset& ds, std::size_t step, std::size_t count) {
  auto orb = cv::ORB::create(1000);
  Stats s;
  std::size_t n = 0;
  for (std::size_t i = 0; i < ds.size() && n < count; i += step, ++n) {
    cv::Mat gray;
    cv::cvtColor(ds.load_rgb(i), gray, cv::COLOR_BGR2GRAY);
    std::vector<cv::KeyPoint> kps;
    orb->detect(gray, kps);
    s.features += static_cast<double>(kps.size());
    // Uncapped texture density: FAST corners at ORB-SLAM's first threshold (20).
    std::vector<cv::KeyPoint> corners;
    cv::FAST(gray, corners, 20, true);
    s.fast20 += static_cast<double>(corners.size());
    const cv::Mat d = ds.load_depth(i);
    s.valid += static_cast<double>(cv::countNonZero(d > 0)) / static_cast<double>(d.total());
    // Share of 16x16 cells with at least one ORB keypoint: how evenly texture is spread.
    cv::Mat cells = cv::Mat::zeros(gray.rows / 16, gray.cols / 16, CV_8U);
    for (const auto& k : kps) cells.at<uint8_t>(std::min(cells.rows - 1, static_cast<int>(k.pt.y / 16)), std::min(cells.cols - 1, static_cast<int>(k.pt.x / 16))) = 1;
    s.texture_fraction += static_cast<double>(cv::countNonZero(cells)) / static_cast<double>(cells.total());
  }
  s.features /= static_cast<double>(n);
  s.valid /= static_cast<double>(n);
  s.texture_fraction /= static_cast<double>(n);
  s.fast20 /= static_cast<double>(n);
  return s;
}

}  // namespace

TEST(RgbdRealism, LabRoomOrbAndValidDepthSameOrderAsSevenScenesKitchen) {
  const std::filesystem::path real = std::filesystem::path(BUILTSCENE_SOURCE_DIR) / "../shared/data/7scenes-kitchen";
  if (!std::filesystem::exists(real / "rgb.txt")) GTEST_SKIP() << "real data not present: " << real;
  synth::RgbdSequenceOptions o;
  o.scene = "lab-room";
  o.out = synth_test::temp_dir("realism");
  o.frames = 150;
  o.seed = 1;
  o.render_threads = 2;
  synth::generate_rgbd_sequence(o);
  const Stats gen = measure(bs::TumDataset::open(o.out), 3, 50);
  const Stats kit = measure(bs::TumDataset::open(real), 20, 50);
  std::cerr << "ORB (1000 max) features/frame: lab-room " << gen.features << ", 7scenes-kitchen " << kit.features << "\n"
            << "valid depth fraction: lab-room " << gen.valid << ", 7scenes-kitchen " << kit.valid << "\n"
            << "FAST-20 corners/frame: lab-room " << gen.fast20 << ", 7scenes-kitchen " << kit.fast20 << "\n"
            << "16x16 cells with a keypoint: lab-room " << gen.texture_fraction << ", 7scenes-kitchen " << kit.texture_fraction << "\n";
  RecordProperty("lab_orb", std::to_string(gen.features));
  RecordProperty("kitchen_orb", std::to_string(kit.features));
  RecordProperty("lab_valid", std::to_string(gen.valid));
  RecordProperty("kitchen_valid", std::to_string(kit.valid));
  EXPECT_GT(gen.features, kit.features / 3);
  EXPECT_LT(gen.features, kit.features * 3);
  EXPECT_GT(gen.fast20, kit.fast20 / 3);
  EXPECT_LT(gen.fast20, kit.fast20 * 3);
  EXPECT_GT(gen.valid, kit.valid / 3);
  EXPECT_LT(gen.valid, std::min(1.0, kit.valid * 3));
  std::filesystem::remove_all(o.out);
}
