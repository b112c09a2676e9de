#pragma once
// Carries an occupancy grid into another ground frame, for scoring a grid built in one world
// (a SLAM's) against a truth map of another (a generated world's): every cell of the output
// takes the value of the source cell under its centre (nearest neighbour).
#include "core/se3.hpp"
#include "ogm/ground_frame.hpp"
#include "ogm/occupancy_grid.hpp"

namespace builtscene {

// The part of a rigid motion between two z-up frames that acts in the floor plane: the
// translation's x and y and the rotation about z (any residual tilt is dropped).
Pose2D planar_part(const SE3& T);

// `src` seen from a frame where a source point p lies at T_dst_src * p. The output covers the
// whole moved source and lies on the lattice of `lattice` (its resolution, and cell corners
// at its origin plus whole cells), so its cells line up with that grid's.
OccupancyGrid resample_grid(const OccupancyGrid& src, const Pose2D& T_dst_src, const OccupancyGrid& lattice);

}  // namespace builtscene
