#pragma once
// The disparity noise a map's own depth readings show: for every stereo measurement of a
// bundle-adjustment problem, the residual between the disparity its point predicts (bf / z in
// the camera) and the one measured (u - u_right); their robust spread is 1.4826 times the
// median absolute residual (the standard deviation of Gaussian noise, unmoved by the few
// readings that disagree by much). The final bundle adjustment of a SLAM run weighs the
// readings with it (LoopCloser::refine_map): a sensor whose depth is better than
// DisparitySigma (which also covers tracking's fixed-map error) is then trusted as much as it
// deserves, and readings that disagree with their point by more than the sensor's noise are
// rejected, whatever the sensor.
#include "slam/local_bundle_adjuster.hpp"

namespace builtscene::slam {

struct DisparityNoise {
  int readings = 0;   // stereo measurements with their point in front of the camera
  double sigma = 0;   // pixels; 0 when fewer than `min_readings`
};

// `min_reads_per_point` > 1 counts only the readings of points read by at least that many
// cameras of the problem: a point made from one camera's reading agrees with it exactly (a
// zero residual that says nothing about the sensor) until another reading joins it.
DisparityNoise estimate_disparity_noise(const BundleAdjustmentProblem& problem, int min_readings = 100,
                                        int min_reads_per_point = 1);

}  // namespace builtscene::slam
