#pragma once
// Least-squares similarity or rigid alignment of corresponding point sets (Umeyama 1991):
// finds T minimizing sum |dst_i - T * src_i|^2.
#include <vector>

#include <Eigen/Core>

#include "core/sim3.hpp"

namespace builtscene {

// Requires at least 3 non-collinear pairs (fewer -> InputError). with_scale=false gives SE3.
Sim3 umeyama_alignment(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                       bool with_scale);

}  // namespace builtscene
