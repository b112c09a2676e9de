#pragma once
// Pictures of a generated sequence for people: RGB and colour-mapped depth side by side,
// and the truth map enlarged.
#include <filesystem>
#include <vector>

#include <opencv2/core.hpp>

namespace builtscene::synth {

// Rows of (RGB | depth) for the given frame indices of a folder written by synth rgbd,
// scaled by `scale`. Depth colours: near blue -> far red over 0..max_depth m, black = none.
cv::Mat rgbd_contact_sheet(const std::filesystem::path& dir, const std::vector<int>& frames, double scale = 0.5,
                           double max_depth = 6.0);

// The truth map PGM enlarged `scale` times (nearest neighbour), with the ground-truth
// trajectory drawn in red.
cv::Mat truth_map_picture(const std::filesystem::path& dir, int scale = 4);

}  // namespace builtscene::synth
