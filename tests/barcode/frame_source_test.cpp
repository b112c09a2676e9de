#include "barcode/frame_source.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "barcode/scan_pipeline.hpp"
#include "core/errors.hpp"
#include "test_images.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene::barcode {
namespace {
namespace fs = std::filesystem;

fs::path frames_dir(const std::string& name) { return builtscene::testing::scratch_dir("frames_" + name); }

std::string error_of(const fs::path& p) {
  try {
    FrameSource::open(p);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

cv::Mat label_frame(const std::string& text) {
  cv::Mat f(240, 320, CV_8UC3, cv::Scalar::all(120));
  cv::Mat sym = synth::render_barcode(text, "Code128", 2, 25);
  cv::copyMakeBorder(sym, sym, 6, 6, 6, 6, cv::BORDER_CONSTANT, cv::Scalar(255));
  cv::Mat bgr;
  cv::cvtColor(sym, bgr, cv::COLOR_GRAY2BGR);
  bgr.copyTo(f(cv::Rect(20, 60, bgr.cols, bgr.rows)));
  return f;
}

TEST(FrameSource, BadInputsGiveOneLineErrorsNamingTheFile) {
  const fs::path d = frames_dir("bad");
  EXPECT_NE(error_of(d / "missing.avi").find("missing.avi"), std::string::npos);
  fs::create_directories(d / "empty");
  EXPECT_NE(error_of(d / "empty").find("no image files"), std::string::npos);
  fs::create_directories(d / "text");
  std::ofstream(d / "text" / "notes.txt") << "hello";
  EXPECT_NE(error_of(d / "text").find("no image files"), std::string::npos);
  std::ofstream(d / "fake.avi") << "this is not a video";
  EXPECT_NE(error_of(d / "fake.avi").find("fake.avi"), std::string::npos);
  std::ofstream(d / "zero.avi");
  EXPECT_NE(error_of(d / "zero.avi").find("zero.avi"), std::string::npos);
  for (const auto& msg : {error_of(d / "missing.avi"), error_of(d / "fake.avi")})
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  fs::remove_all(d);
}

TEST(FrameSource, FolderInNaturalOrderAndVideoWithRawPackets) {
  const fs::path d = frames_dir("ok");
  for (int i : {10, 2, 1}) cv::imwrite((d / (std::to_string(i) + ".png")).string(), cv::Mat(8, 8, CV_8UC3, cv::Scalar::all(i)));
  std::ofstream(d / "truth.csv") << "ignored";
  auto src = FrameSource::open(d);
  EXPECT_EQ(src->expected_frames(), 3u);
  cv::Mat f;
  std::vector<int> order;
  while (src->read(f)) order.push_back(f.at<cv::Vec3b>(0, 0)[0]);
  EXPECT_EQ(order, (std::vector<int>{1, 2, 10}));

  const fs::path video = d / "v.avi";
  cv::VideoWriter w(video.string(), cv::CAP_FFMPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10, cv::Size(320, 240));
  ASSERT_TRUE(w.isOpened());
  for (int i = 0; i < 6; ++i) w.write(label_frame("RM140" + std::to_string(i) + "A"));
  w.release();
  auto vs = FrameSource::open(video);
  EXPECT_EQ(vs->expected_frames(), 6u);
  EncodedFrame ef;
  std::size_t n = 0;
  while (vs->read_encoded(ef)) {
    const cv::Mat g = decode_gray(ef);
    EXPECT_EQ(g.size(), cv::Size(320, 240));
    ++n;
  }
  EXPECT_EQ(n, 6u);
  fs::remove_all(d);
}

// Bad input in the middle of a scan: a clear error naming the file, and the inventory keeps
// exactly what was read before it.
TEST(FrameSource, CorruptImageMidScanKeepsWhatWasFound) {
  const fs::path d = frames_dir("mid");
  cv::imwrite((d / "000.png").string(), label_frame("RM1401A"));
  cv::imwrite((d / "001.png").string(), label_frame("RM1402A"));
  std::ofstream(d / "002.png") << "not a png";
  cv::imwrite((d / "003.png").string(), label_frame("RM1403A"));
  ScanOptions o;
  o.out = d / "out";
  o.keyframes = "off";
  o.region = "0.6";
  try {
    scan(d, o);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("002.png"), std::string::npos) << e.what();
  }
  const Inventory inv = Inventory::read_csv(o.out / "inventory.csv");
  EXPECT_TRUE(inv.contains("RM1401A", "Code128"));
  EXPECT_TRUE(inv.contains("RM1402A", "Code128"));
  EXPECT_FALSE(inv.contains("RM1403A", "Code128"));
  fs::remove_all(d);
}

TEST(FrameSource, TruncatedVideoIsAnErrorAfterItsGoodFrames) {
  const fs::path d = frames_dir("trunc");
  const fs::path video = d / "t.avi";
  {
    cv::VideoWriter w(video.string(), cv::CAP_FFMPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10, cv::Size(320, 240));
    ASSERT_TRUE(w.isOpened());
    for (int i = 0; i < 20; ++i) w.write(label_frame("RM1501B"));
  }
  fs::resize_file(video, fs::file_size(video) / 2);
  ScanOptions o;
  o.out = d / "out";
  o.keyframes = "off";
  o.region = "0.6";
  std::string msg;
  try {
    scan(video, o);
  } catch (const InputError& e) {
    msg = e.what();
  }
  EXPECT_NE(msg.find("t.avi"), std::string::npos) << "no error for a truncated video: '" << msg << "'";
  ASSERT_TRUE(fs::exists(o.out / "inventory.csv"));
  EXPECT_TRUE(Inventory::read_csv(o.out / "inventory.csv").contains("RM1501B", "Code128"));
  fs::remove_all(d);
}

}  // namespace
}  // namespace builtscene::barcode
