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

}  // namespace builtscene
