#pragma once
// TUM trajectory files: one line per pose, `timestamp tx ty tz qx qy qz qw`, camera in world;
// '#' starts a comment line.
#include <filesystem>
#include <vector>

#include "core/se3.hpp"

namespace builtscene {

struct StampedPose {
  double timestamp = 0;
  SE3 pose;  // T_wc
};
using Trajectory = std::vector<StampedPose>;

// Throws InputError naming the file and line for malformed lines, non-finite values, a
// quaternion far from unit length, or (when `require_nonempty`) a file without poses.
Trajectory read_tum_trajectory(const std::filesystem::path& path, bool require_nonempty = true);
void write_tum_trajectory(const std::filesystem::path& path, const Trajectory& trajectory);

}  // namespace builtscene
