#pragma once
// Procedural textures of indoor materials, deterministic for a seed. They are built to give
// FAST/ORB what real rooms give: many corners on posters, books, text and tiles, few on
// paint and concrete, at several scales (the renderer mip-maps them).
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace builtscene::synth {

// Kinds: paint, concrete, floor_tiles, lino, ceiling_tiles, wood, carpet, metal, poster,
// whiteboard, books, door, corkboard, screen, sign, brick. `base` tints plain kinds (BGR).
cv::Mat generate_texture(const std::string& kind, std::uint64_t seed, int size = 512,
                         cv::Scalar base = cv::Scalar(200, 205, 210));
std::vector<std::string> texture_kinds();

}  // namespace builtscene::synth
