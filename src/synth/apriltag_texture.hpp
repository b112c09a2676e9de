#pragma once
// Images of real tag36h11 codes, drawn from libapriltag's family description.
#include <opencv2/core.hpp>

namespace builtscene::synth {

int tag36h11_code_count();
// The tag with its one-cell white border: 10 x 10 cells of cell_px pixels, 8-bit BGR,
// image top row = the tag's top as printed by libapriltag. Throws for an id out of range.
cv::Mat tag36h11_image(int id, int cell_px);

}  // namespace builtscene::synth
