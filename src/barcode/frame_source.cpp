#include "barcode/frame_source.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <iterator>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "core/errors.hpp"

namespace builtscene::barcode {
namespace fs = std::filesystem;

namespace {

bool is_image_name(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".tif" || ext == ".tiff" ||
         ext == ".pgm" || ext == ".ppm";
}

// Natural order: digit runs compare by value.
bool natural_less(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (std::isdigit(static_cast<unsigned char>(a[i])) && std::isdigit(static_cast<unsigned char>(b[j]))) {
      std::size_t i2 = i, j2 = j;
      while (i2 < a.size() && std::isdigit(static_cast<unsigned char>(a[i2]))) ++i2;
      while (j2 < b.size() && std::isdigit(static_cast<unsigned char>(b[j2]))) ++j2;
      std::string na = a.substr(i, i2 - i), nb = b.substr(j, j2 - j);
      na.erase(0, std::min(na.find_first_not_of('0'), na.size()));
      nb.erase(0, std::min(nb.find_first_not_of('0'), nb.size()));
      if (na.size() != nb.size()) return na.size() < nb.size();
      if (na != nb) return na < nb;
      i = i2, j = j2;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i, ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

class ImageFolderSource final : public FrameSource {
 public:
  explicit ImageFolderSource(const fs::path& dir) : FrameSource(dir), files_(list_image_files(dir)) {
    if (files_.empty())
      throw InputError(located(dir, 0, "no image files (png, jpg, bmp, tif, pgm, ppm) in this folder"));
  }
  std::size_t expected_frames() const override { return files_.size(); }
  bool read(cv::Mat& frame) override {
    if (next_ >= files_.size()) return false;
    const fs::path& f = files_[next_];
    frame = cv::imread(f.string(), cv::IMREAD_COLOR);
    if (frame.empty()) throw InputError(located(f, 0, "not a readable image (frame " + std::to_string(next_) + ")"));
    ++next_;
    return true;
  }
  bool read_encoded(EncodedFrame& frame) override {
    if (next_ >= files_.size()) return false;
    const fs::path& f = files_[next_];
    std::ifstream in(f, std::ios::binary);
    if (!in) throw InputError(located(f, 0, "cannot open image file"));
    frame.bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    frame.image.release();
    frame.origin = f;
    frame.index = next_++;
    return true;
  }
  bool skip() override {
    if (next_ >= files_.size()) return false;
    ++next_;
    return true;
  }
  void rewind() override { next_ = 0; }
  std::size_t position() const override { return next_; }
  fs::path current_file() const override { return next_ < files_.size() ? files_[next_] : path_; }

 private:
  std::vector<fs::path> files_;
  std::size_t next_ = 0;
};

class VideoFileSource final : public FrameSource {
 public:
  explicit VideoFileSource(const fs::path& file) : FrameSource(file) {
    reopen();
    const double n = cap_.get(cv::CAP_PROP_FRAME_COUNT);
    expected_ = n > 0 ? static_cast<std::size_t>(n + 0.5) : 0;
    if (expected_ == 0) {
      // Some containers have no count: probe for a first frame.
      cv::Mat probe;
      if (!cap_.read(probe) || probe.empty()) throw InputError(located(file, 0, "video has no frames"));
      reopen();
    }
  }
  std::size_t expected_frames() const override { return expected_; }
  bool read(cv::Mat& frame) override {
    EncodedFrame f;
    if (!read_encoded(f)) return false;
    frame = f.image.empty() ? cv::imdecode(f.bytes, cv::IMREAD_COLOR) : f.image;
    if (frame.empty()) throw InputError(located(path_, 0, "frame " + std::to_string(f.index) + " cannot be decoded"));
    return true;
  }
  bool read_encoded(EncodedFrame& frame) override {
    cv::Mat m;
    if (!cap_.read(m) || m.empty()) return end_of_video();
    frame.origin = path_;
    frame.index = next_++;
    if (raw_) {
      frame.bytes.assign(m.datastart, m.dataend);
      frame.image.release();
    } else {
      frame.bytes.clear();
      frame.image = m;
    }
    return true;
  }
  bool skip() override {
    if (!cap_.grab()) return end_of_video();
    ++next_;
    return true;
  }
  void rewind() override { reopen(); }
  std::size_t position() const override { return next_; }
  fs::path current_file() const override { return path_; }

 private:
  void reopen() {
    cap_.release();
    // MJPG packets are whole JPEG images: take them undecoded (skipping is then free and the
    // decoding moves to the worker threads). Any other codec is decoded here.
    raw_ = false;
    if (cap_.open(path_.string(), cv::CAP_FFMPEG, {cv::CAP_PROP_FORMAT, -1}) && cap_.isOpened()) {
      const auto fourcc = static_cast<int>(cap_.get(cv::CAP_PROP_FOURCC));
      if (fourcc == cv::VideoWriter::fourcc('M', 'J', 'P', 'G')) raw_ = true;
    }
    if (!raw_) {
      cap_.release();
      if (!cap_.open(path_.string(), cv::CAP_FFMPEG) || !cap_.isOpened())
        throw InputError(located(path_, 0, "cannot open as a video (not a video, unsupported codec or corrupt header)"));
    }
    next_ = 0;
  }
  bool end_of_video() {
    if (next_ == 0) throw InputError(located(path_, 0, "video has no decodable frames"));
    if (expected_ > 0 && next_ < expected_)
      throw InputError(located(path_, 0, "truncated or corrupt video: frame " + std::to_string(next_) +
                                             " cannot be decoded (header says " + std::to_string(expected_) +
                                             " frames)"));
    return false;
  }
  cv::VideoCapture cap_;
  bool raw_ = false;
  std::size_t expected_ = 0;
  std::size_t next_ = 0;
};

}  // namespace

cv::Mat decode_gray(const EncodedFrame& frame, int reduce) {
  cv::Mat gray;
  if (!frame.image.empty()) {
    if (frame.image.channels() == 3) {
      cv::cvtColor(frame.image, gray, cv::COLOR_BGR2GRAY);
    } else {
      gray = frame.image;
    }
    if (reduce > 1) cv::resize(gray, gray, cv::Size(), 1.0 / reduce, 1.0 / reduce, cv::INTER_AREA);
    return gray;
  }
  int flag = cv::IMREAD_GRAYSCALE;
  if (reduce == 2) flag = cv::IMREAD_REDUCED_GRAYSCALE_2;
  if (reduce == 4) flag = cv::IMREAD_REDUCED_GRAYSCALE_4;
  if (reduce >= 8) flag = cv::IMREAD_REDUCED_GRAYSCALE_8;
  if (!frame.bytes.empty()) gray = cv::imdecode(frame.bytes, flag);
  if (gray.empty())
    throw InputError(located(frame.origin, 0, "frame " + std::to_string(frame.index) + " is not a decodable image"));
  return gray;
}

std::vector<fs::path> list_image_files(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_regular_file() && is_image_name(e.path())) files.push_back(e.path());
  std::sort(files.begin(), files.end(),
            [](const fs::path& a, const fs::path& b) { return natural_less(a.filename().string(), b.filename().string()); });
  return files;
}

std::unique_ptr<FrameSource> FrameSource::open(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(located(path, 0, "no such file or folder"));
  if (fs::is_directory(path, ec)) return std::make_unique<ImageFolderSource>(path);
  if (fs::file_size(path, ec) == 0) throw InputError(located(path, 0, "empty file, not a video"));
  return std::make_unique<VideoFileSource>(path);
}

}  // namespace builtscene::barcode
