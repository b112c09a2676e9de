#pragma once
// A deterministic textured test image: random filled shapes of random grey levels, lightly
// blurred, so corners exist at all scales and every part of the image has some texture.
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace builtscene::test {

inline cv::Mat textured_image(int width, int height, std::uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat img(height, width, CV_8UC1, cv::Scalar(128));
  for (int i = 0; i < 700; ++i) {
    const cv::Point c(rng.uniform(0, width), rng.uniform(0, height));
    const int r = rng.uniform(3, 40);
    const cv::Scalar g(rng.uniform(0, 256));
    if (i % 3 == 0) {
      cv::circle(img, c, r, g, cv::FILLED, cv::LINE_AA);
    } else {
      const cv::RotatedRect rr(cv::Point2f(c), cv::Size2f(static_cast<float>(r * 2), static_cast<float>(rng.uniform(3, 40))),
                               static_cast<float>(rng.uniform(0, 180)));
      cv::Point2f pts[4];
      rr.points(pts);
      std::vector<cv::Point> poly(pts, pts + 4);
      cv::fillConvexPoly(img, poly, g, cv::LINE_AA);
    }
  }
  cv::GaussianBlur(img, img, cv::Size(3, 3), 0.8);
  return img;
}

}  // namespace builtscene::test
