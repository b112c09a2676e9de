// Turbulent wind speed by the spectral representation method (Shinozuka & Deodatis 1991)
// of the one-sided Kaimal spectrum (Kaimal et al. 1972):
//   f S(f) / u*^2 = 200 x / (1 + 50 x)^(5/3),  x = f z / U,  u* = kappa U / ln(z / z0)
//   u(t) = sum_k sqrt(2 S(f_k) df) cos(2 pi f_k t + phi_k),  f_k = (k - 1/2) df
// Its variance integrates to 6 u*^2 over all frequencies.
#pragma once
#include <cmath>
#include <cstdint>
#include <vector>

namespace wsc {

struct KaimalWind {
  double mean = 0, z = 0, z0 = 0;
  double friction_velocity() const { return 0.4 * mean / std::log(z / z0); }
  double spectrum(double f) const {  // S(f) [m^2/s^2/Hz]
    const double us = friction_velocity();
    return 200 * us * us * (z / mean) / std::pow(1 + 50 * f * z / mean, 5.0 / 3.0);
  }
  // Integral of S from 0 to f (closed form).
  double variance_below(double f) const {
    const double us = friction_velocity();
    return 6 * us * us * (1 - std::pow(1 + 50 * f * z / mean, -2.0 / 3.0));
  }
};

struct SpectralSeries {
  std::vector<double> freq, amp, phase;
  double df = 0;
  SpectralSeries(const KaimalWind& w, int n, double f_max, uint64_t seed) : df(f_max / n) {
    uint64_t s = seed;
    auto uniform = [&s] {  // splitmix64: the same phases on every platform
      uint64_t z = (s += 0x9E3779B97F4A7C15ull);
      z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
      z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
      z ^= z >> 31;
      return static_cast<double>(z >> 11) * 0x1.0p-53;
    };
    for (int k = 1; k <= n; ++k) {
      const double f = (k - 0.5) * df;
      freq.push_back(f);
      amp.push_back(std::sqrt(2 * w.spectrum(f) * df));
      phase.push_back(2 * M_PI * uniform());
    }
  }
  double operator()(double t) const {
    double u = 0;
    for (std::size_t k = 0; k < freq.size(); ++k) u += amp[k] * std::cos(2 * M_PI * freq[k] * t + phase[k]);
    return u;
  }
};

}  // namespace wsc
