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

}  // namespace builtscene
