#include "features/orb_pattern.hpp"

#include <cmath>
#include <random>

namespace builtscene {
namespace {

std::array<BriefPair, kBriefPairs> make_pattern() {
  // std::mt19937 is specified bit-exactly by the standard; the Gaussian is produced here by
  // Box-Muller from its raw output so the pattern does not depend on the library's
  // normal_distribution implementation.
  std::mt19937 rng(0x0B51E5u);
  const double sigma = 9.0;
  auto uniform = [&rng] { return (static_cast<double>(rng()) + 0.5) / 4294967296.0; };
  auto sample = [&](std::int8_t& x, std::int8_t& y) {
    for (;;) {
      const double r = std::sqrt(-2.0 * std::log(uniform())) * sigma;
      const double a = 2.0 * M_PI * uniform();
      const long px = std::lround(r * std::cos(a)), py = std::lround(r * std::sin(a));
      if (px * px + py * py <= static_cast<long>(kOrbPatchRadius - 1) * (kOrbPatchRadius - 1)) {
        x = static_cast<std::int8_t>(px);
        y = static_cast<std::int8_t>(py);
        return;
      }
    }
  };
  std::array<BriefPair, kBriefPairs> p{};
  for (auto& pair : p) {
    do {
      sample(pair.x1, pair.y1);
      sample(pair.x2, pair.y2);
    } while ((pair.x1 - pair.x2) * (pair.x1 - pair.x2) + (pair.y1 - pair.y2) * (pair.y1 - pair.y2) < 25);
  }
  return p;
}

}  // namespace

const std::array<BriefPair, kBriefPairs>& orb_brief_pattern() {
  static const std::array<BriefPair, kBriefPairs> pattern = make_pattern();
  return pattern;
}

RotatedBriefTable::RotatedBriefTable() {
  const auto& base = orb_brief_pattern();
  for (int b = 0; b < kBins; ++b) {
    const double a = b * (2.0 * M_PI / kBins);
    const double c = std::cos(a), s = std::sin(a);
    auto rot = [&](std::int8_t x, std::int8_t y, std::int8_t& u, std::int8_t& v) {
      u = static_cast<std::int8_t>(std::lround(x * c - y * s));
      v = static_cast<std::int8_t>(std::lround(x * s + y * c));
    };
    for (int i = 0; i < kBriefPairs; ++i) {
      const BriefPair& p = base[static_cast<std::size_t>(i)];
      BriefPair& r = rotated_[static_cast<std::size_t>(b)][static_cast<std::size_t>(i)];
      rot(p.x1, p.y1, r.x1, r.y1);
      rot(p.x2, p.y2, r.x2, r.y2);
    }
  }
}

const BriefPair* RotatedBriefTable::pairs(float angle_deg) const {
  long bin = std::lround(angle_deg * (kBins / 360.0f)) % kBins;
  if (bin < 0) bin += kBins;
  return rotated_[static_cast<std::size_t>(bin)].data();
}

const RotatedBriefTable& rotated_pattern_table() {
  static const RotatedBriefTable table;
  return table;
}

}  // namespace builtscene
