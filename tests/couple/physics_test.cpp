// The example's physics against closed-form answers: Newmark's average-acceleration
// step on an SDOF under a constant and a harmonic force vs the analytic response, and the
// simulated wind's variance vs the integral of the Kaimal spectrum.
#include <gtest/gtest.h>

#include <cmath>

#include "../../examples/coupling/wind-structure-control/models/common/kaimal.hpp"
#include "../../examples/coupling/wind-structure-control/models/common/sdof.hpp"

TEST(Newmark, StepLoadFromRestMatchesTheAnalyticResponse) {
  const auto s = wsc::Sdof::from(3e5, 0.5, 0.02);
  const double F0 = 1e5, dt = 0.01, zeta = 0.02, w = M_PI, wd = w * std::sqrt(1 - zeta * zeta);
  wsc::SdofState x;  // at rest; the force switches on at t = 0+
  x.A = F0 / s.m;
  double max_err = 0;
  for (int n = 1; n <= 2000; ++n) {
    x = wsc::newmark_step(s, x, F0, dt);
    const double t = n * dt;
    // Chopra eq. 4.1.x: u(t) = u_st [1 - e^{-zeta w t} (cos wd t + zeta/sqrt(1-zeta^2) sin wd t)]
    const double exact = F0 / s.k * (1 - std::exp(-zeta * w * t) * (std::cos(wd * t) + zeta / std::sqrt(1 - zeta * zeta) * std::sin(wd * t)));
    max_err = std::max(max_err, std::abs(x.D - exact));
  }
  // Average acceleration is second-order accurate: the error is (w dt)^2-small.
  EXPECT_LT(max_err / (F0 / s.k), 2e-3);
}

TEST(Newmark, HarmonicForceReachesTheSteadyStateAmplitude) {
  const auto s = wsc::Sdof::from(3e5, 0.5, 0.05);
  const double F0 = 1e4, dt = 0.005, w = M_PI, W = 0.8 * w, zeta = 0.05;
  wsc::SdofState x;
  double amp = 0;
  for (int n = 1; n <= 40000; ++n) {  // 200 s: the transient has decayed
    x = wsc::newmark_step(s, x, F0 * std::sin(W * n * dt), dt);
    if (n > 30000) amp = std::max(amp, std::abs(x.D));
  }
  const double r = W / w;
  const double exact = F0 / s.k / std::sqrt((1 - r * r) * (1 - r * r) + (2 * zeta * r) * (2 * zeta * r));
  EXPECT_NEAR(amp / exact, 1.0, 2e-3);
}

TEST(KaimalWind, SampleVarianceEqualsTheSpectrumIntegral) {
  const wsc::KaimalWind w{30.0, 100.0, 0.3};
  const int n = 2048;  // as in the example (wind.yaml)
  const double f_max = 5.0;
  const wsc::SpectralSeries u(w, n, f_max, 11);
  // Over one period of the series (2 / df) the sampled variance is exactly sum S(f_k) df,
  // the midpoint rule for the integral of S; compare with the closed-form integral.
  const double period = 2.0 / u.df, dt = 0.1;
  const int samples = static_cast<int>(std::lround(period / dt));
  double sum = 0, sum2 = 0;
  for (int i = 0; i < samples; ++i) {
    const double v = u(i * dt);
    sum += v;
    sum2 += v * v;
  }
  const double mean = sum / samples, var = sum2 / samples - mean * mean;
  EXPECT_NEAR(mean, 0.0, 1e-9 * std::sqrt(var));
  double midpoint = 0;
  for (int k = 1; k <= n; ++k) midpoint += w.spectrum((k - 0.5) * u.df) * u.df;
  EXPECT_NEAR(var / midpoint, 1.0, 1e-9);
  // The midpoint rule misses part of the steep low-frequency peak: under 1% here.
  EXPECT_NEAR(var / w.variance_below(f_max), 1.0, 0.01);
  // and the spectrum holds most of the 6 u*^2 of the full Kaimal spectrum
  const double us = w.friction_velocity();
  EXPECT_GT(var / (6 * us * us), 0.8);
}
