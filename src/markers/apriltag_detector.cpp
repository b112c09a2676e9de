#include "markers/apriltag_detector.hpp"

#include <cstdlib>
#include <mutex>

#include <opencv2/imgproc.hpp>

extern "C" {
#include <apriltag/apriltag.h>
#include <apriltag/tag16h5.h>
#include <apriltag/tag25h9.h>
#include <apriltag/tag36h11.h>
#include <apriltag/tagCircle21h7.h>
#include <apriltag/tagStandard41h12.h>
}

#include "core/errors.hpp"

namespace builtscene {

struct AprilTagDetector::Impl {
  apriltag_family_t* family = nullptr;
  void (*destroy_family)(apriltag_family_t*) = nullptr;
  apriltag_detector_t* detector = nullptr;
  std::mutex mutex;  // libapriltag's detector is not reentrant
};

AprilTagDetector::AprilTagDetector(AprilTagOptions options) : options_(std::move(options)), impl_(std::make_unique<Impl>()) {
  const std::string& f = options_.family;
  if (f == "tag36h11") impl_->family = tag36h11_create(), impl_->destroy_family = tag36h11_destroy;
  else if (f == "tag25h9") impl_->family = tag25h9_create(), impl_->destroy_family = tag25h9_destroy;
  else if (f == "tag16h5") impl_->family = tag16h5_create(), impl_->destroy_family = tag16h5_destroy;
  else if (f == "tagCircle21h7") impl_->family = tagCircle21h7_create(), impl_->destroy_family = tagCircle21h7_destroy;
  else if (f == "tagStandard41h12") impl_->family = tagStandard41h12_create(), impl_->destroy_family = tagStandard41h12_destroy;
  else throw InputError("--tag-family: unknown AprilTag family '" + f + "' (tag36h11, tag25h9, tag16h5, tagCircle21h7, tagStandard41h12)");
  impl_->detector = apriltag_detector_create();
  apriltag_detector_add_family_bits(impl_->detector, impl_->family, options_.max_hamming);
  impl_->detector->quad_decimate = options_.decimate;
  impl_->detector->quad_sigma = options_.blur_sigma;
  impl_->detector->nthreads = options_.threads;
  impl_->detector->refine_edges = options_.refine_edges;
}

AprilTagDetector::~AprilTagDetector() {
  if (impl_->detector) apriltag_detector_destroy(impl_->detector);
  if (impl_->family) impl_->destroy_family(impl_->family);
}

std::vector<TagDetection> AprilTagDetector::detect(const cv::Mat& image) const {
  cv::Mat gray;
  if (image.channels() == 3) cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  else if (image.channels() == 4) cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
  else gray = image;
  if (gray.type() != CV_8UC1) throw InputError("AprilTag detection needs an 8-bit image");
  const double scale = options_.upsample > 1 ? options_.upsample : 1;
  if (scale > 1) cv::resize(gray, gray, {}, scale, scale, cv::INTER_CUBIC);
  if (!gray.isContinuous()) gray = gray.clone();
  image_u8_t im{gray.cols, gray.rows, static_cast<int32_t>(gray.step[0]), gray.data};
  std::vector<TagDetection> out;
  std::lock_guard lock(impl_->mutex);
  zarray_t* dets = apriltag_detector_detect(impl_->detector, &im);
  for (int i = 0; i < zarray_size(dets); ++i) {
    apriltag_detection_t* d;
    zarray_get(dets, i, &d);
    if (d->hamming > options_.max_hamming) continue;
    TagDetection t;
    t.id = d->id;
    t.hamming = d->hamming;
    t.decision_margin = d->decision_margin;
    // libapriltag puts pixel centres at half-integers (the top-left pixel spans [0, 1]);
    // OpenCV at integers.
    // An upsampled image scales libapriltag's continuous coordinates exactly.
    t.center = {d->c[0] / scale - 0.5, d->c[1] / scale - 0.5};
    for (int k = 0; k < 4; ++k) t.corners[static_cast<std::size_t>(k)] = {d->p[k][0] / scale - 0.5, d->p[k][1] / scale - 0.5};
    out.push_back(t);
  }
  apriltag_detections_destroy(dets);
  std::sort(out.begin(), out.end(), [](const TagDetection& a, const TagDetection& b) {
    return a.id != b.id ? a.id < b.id : a.center.x() < b.center.x();
  });
  return out;
}

cv::Mat AprilTagDetector::render_tag(int id) const {
  if (id < 0 || static_cast<uint32_t>(id) >= impl_->family->ncodes)
    throw InputError("tag id " + std::to_string(id) + " is not in family " + options_.family);
  image_u8_t* img = apriltag_to_image(impl_->family, id);
  cv::Mat out(img->height, img->width, CV_8UC1);
  for (int r = 0; r < img->height; ++r)
    for (int c = 0; c < img->width; ++c) out.at<std::uint8_t>(r, c) = img->buf[r * img->stride + c];
  // image_u8_destroy is not exported by Debian's libapriltag; the image and its buffer come
  // from calloc (image_u8_create_stride), so free both.
  std::free(img->buf);
  std::free(img);
  return out;
}

}  // namespace builtscene
