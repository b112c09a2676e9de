#pragma once
// The rotated-BRIEF sampling pattern: 256 point pairs inside a disk of radius 15 around a
// keypoint. Drawn once from an isotropic Gaussian (BRIEF's "G II" layout) with a fixed seed,
// so every build and run produces the same descriptors. The disk keeps every rotated pair
// inside the patch that orientation estimation also uses. sigma = 9 and pairs at least 5 px
// long: measured on the rotated/scaled pairs of tests/features (longer pairs suffer less
// from rounding the rotated pattern to pixels) against BRIEF's sigma = 31/5 without a length
// limit. OpenCV's learned pattern still matches better under rotation; learning our own
// pattern (greedy low-correlation selection, as the ORB paper does) is future work.
#include <array>
#include <cstdint>

namespace builtscene {

struct BriefPair {
  std::int8_t x1, y1, x2, y2;
};

constexpr int kBriefPairs = 256;
constexpr int kOrbPatchRadius = 15;

const std::array<BriefPair, kBriefPairs>& orb_brief_pattern();

// The pattern rotated to each whole degree and rounded to pixels, computed once: describing a
// keypoint then costs table lookups instead of 512 rotations and roundings (about a third of
// the extraction time before). Rounding the angle to 1 degree moves a sample point by at
// most 0.13 px (radius 15), well under the pixel rounding every rotated pattern has anyway.
class RotatedBriefTable {
 public:
  static constexpr int kBins = 360;
  RotatedBriefTable();
  // The pairs rotated by `angle_deg` (any value; wrapped to [0, 360)), as pixel offsets.
  const BriefPair* pairs(float angle_deg) const;

 private:
  std::array<std::array<BriefPair, kBriefPairs>, kBins> rotated_;
};

const RotatedBriefTable& rotated_pattern_table();

}  // namespace builtscene
