// Real stills (../shared/data/barcodes-real, truth in N.txt), each rotated by 0, 30, 45, 60 and
// 90 degrees and pasted into a larger cluttered frame: the pipeline must read at least as many
// as the decoder alone at every angle. Prints the table.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <map>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "barcode/frame_source.hpp"
#include "barcode/scan_pipeline.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene::barcode {
namespace {
namespace fs = std::filesystem;

struct Still {
  fs::path image;
  std::string text;
};

std::vector<Still> load_stills(const fs::path& root) {
  std::vector<Still> stills;
  for (const auto& dir : fs::directory_iterator(root)) {
    if (!dir.is_directory() || dir.path().filename().string().find("falsepositives") == 0) continue;
    for (const auto& img : list_image_files(dir.path())) {
      fs::path txt = img;
      txt.replace_extension(".txt");
      std::ifstream f(txt);
      std::string text;
      if (!f || !std::getline(f, text)) continue;
      while (!text.empty() && (text.back() == '\r' || text.back() == '\n')) text.pop_back();
      if (!text.empty()) stills.push_back({img, text});
    }
  }
  std::sort(stills.begin(), stills.end(), [](const Still& a, const Still& b) { return a.image < b.image; });
  return stills;
}

// The still turned by `angle` on a cluttered frame at least twice its size.
cv::Mat compose(const cv::Mat& still, double angle, cv::RNG& rng) {
  cv::Mat s = still;
  const double fit = 640.0 / std::max(s.cols, s.rows);
  if (fit < 1.0) cv::resize(s, s, cv::Size(), fit, fit, cv::INTER_AREA);
  const cv::Point2f c(s.cols / 2.0f, s.rows / 2.0f);
  cv::Mat R = cv::getRotationMatrix2D(c, angle, 1.0);
  const cv::Rect2f box = cv::RotatedRect(c, s.size(), static_cast<float>(angle)).boundingRect2f();
  const cv::Size canvas(std::max(960, static_cast<int>(box.width * 1.5)), std::max(720, static_cast<int>(box.height * 1.5)));
  cv::Mat frame(canvas, CV_8UC3, cv::Scalar(90, 100, 110));
  for (int k = 0; k < 40; ++k) {  // clutter: boxes, stripes, noise
    const cv::Point p(rng.uniform(0, canvas.width), rng.uniform(0, canvas.height));
    const cv::Scalar col(rng.uniform(30, 220), rng.uniform(30, 220), rng.uniform(30, 220));
    if (k % 3 == 0) {
      cv::line(frame, p, p + cv::Point(rng.uniform(-200, 200), rng.uniform(-200, 200)), col, rng.uniform(2, 9));
    } else {
      cv::rectangle(frame, cv::Rect(p, cv::Size(rng.uniform(20, 220), rng.uniform(20, 160))), col, cv::FILLED);
    }
  }
  R.at<double>(0, 2) += canvas.width / 2.0 - c.x;
  R.at<double>(1, 2) += canvas.height / 2.0 - c.y;
  cv::Mat warped, mask;
  cv::warpAffine(s, warped, R, canvas, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(255));
  cv::warpAffine(cv::Mat(s.size(), CV_8UC1, cv::Scalar(255)), mask, R, canvas, cv::INTER_NEAREST);
  warped.copyTo(frame, mask);
  return frame;
}

TEST(RealStills, PipelineReadsAtLeastAsManyAsTheDecoderAloneAtEveryAngle) {
  const fs::path root = fs::path(BUILTSCENE_SOURCE_DIR) / ".." / "shared" / "data" / "barcodes-real";
  if (!fs::is_directory(root)) GTEST_SKIP() << "real barcode stills not found at " << root << " (shared data absent)";
  // Every 3rd still keeps the test within its time budget; BUILTSCENE_STILLS_ALL=1 takes all
  // (bench/barcodes_stills.sh does, for the table in docs/barcodes.md).
  auto stills = load_stills(root);
  ASSERT_GT(stills.size(), 50u);
  if (!std::getenv("BUILTSCENE_STILLS_ALL")) {
    std::vector<Still> some;
    for (std::size_t i = 0; i < stills.size(); i += 3) some.push_back(stills[i]);
    stills = some;
  }
  const fs::path tmp = builtscene::testing::scratch_dir("stills");
  std::printf("%6s %8s %14s %10s\n", "angle", "stills", "decoder_only", "pipeline");
  for (double angle : {0.0, 30.0, 45.0, 60.0, 90.0}) {
    fs::remove_all(tmp);
    fs::create_directories(tmp / "frames");
    cv::RNG rng(1234 + static_cast<int>(angle));
    std::size_t n = 0;
    for (const auto& s : stills) {
      const cv::Mat img = cv::imread(s.image.string(), cv::IMREAD_COLOR);
      if (img.empty()) continue;
      char name[32];
      std::snprintf(name, sizeof name, "%05zu.bmp", n++);
      cv::imwrite((tmp / "frames" / name).string(), compose(img, angle, rng));
    }
    auto count = [&](const Inventory& inv) {
      std::size_t ok = 0;
      for (std::size_t i = 0; i < stills.size(); ++i)
        for (const auto* e : inv.entries())
          if (e->code == stills[i].text && std::find(e->frames.begin(), e->frames.end(), i) != e->frames.end()) {
            ++ok;
            break;
          }
      return ok;
    };
    ScanOptions pipe;
    pipe.keyframes = "off";  // stills are unrelated frames, not a video
    ScanOptions alone = pipe;
    alone.decoder_only = true;
    const std::size_t a = count(scan(tmp / "frames", alone).inventory);
    const std::size_t p = count(scan(tmp / "frames", pipe).inventory);
    std::printf("%6.0f %8zu %14zu %10zu\n", angle, n, a, p);
    RecordProperty("angle_" + std::to_string(static_cast<int>(angle)), std::to_string(a) + "/" + std::to_string(p));
    EXPECT_GE(p, a) << "angle " << angle;
  }
  fs::remove_all(tmp);
}

}  // namespace
}  // namespace builtscene::barcode
