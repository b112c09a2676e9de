#pragma once
// The camera of the generated worlds and of most closed-form tests: Kinect-like intrinsics,
// 640 x 480, no distortion.
#include "core/camera.hpp"

namespace builtscene::testing {

inline PinholeCamera kinect_camera() {
  PinholeCamera c;
  c.fx = c.fy = 525.0;
  c.cx = 319.5;
  c.cy = 239.5;
  c.width = 640;
  c.height = 480;
  return c;
}

}  // namespace builtscene::testing
