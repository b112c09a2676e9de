#pragma once
// How much pixel noise an 8-bit grey image carries: the standard deviation of additive white
// noise, estimated from the image alone (Immerkaer 1996, "Fast noise variance estimation").
//
// The mask [1 -2 1; -2 4 -2; 1 -2 1] is the difference of two Laplacians, so it cancels
// intensity ramps and most smooth structure while white noise of sigma passes with a standard
// deviation of 6 sigma. Immerkaer averages |response|; this takes the median instead, so the
// edges and corners of a textured scene (a minority of pixels) do not raise the estimate.
#include <opencv2/core.hpp>

namespace builtscene {

// sigma in grey levels; 0 for an image smaller than 3 x 3. `step` samples every step-th row
// and column (2 reads a quarter of the pixels). Requires CV_8UC1.
double estimate_image_noise_sigma(const cv::Mat& gray, int step = 2);

}  // namespace builtscene
