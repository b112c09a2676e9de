#pragma once
// Coloured point clouds: binary little-endian PLY (x y z float, red green blue uchar), and
// voxel-grid downsampling (one point per occupied voxel: the mean position and colour).
#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

#include <Eigen/Core>

namespace builtscene {

struct ColoredPoint {
  Eigen::Vector3f position;
  std::array<std::uint8_t, 3> rgb{};
};
using PointCloud = std::vector<ColoredPoint>;

void write_ply(const std::filesystem::path& path, const PointCloud& cloud);
// Reads binary little-endian or ASCII PLY with float/double x y z and optional uchar colour;
// InputError naming the file on anything else.
PointCloud read_ply(const std::filesystem::path& path);

PointCloud voxel_downsample(const PointCloud& cloud, double voxel_size);

}  // namespace builtscene
