// Single-degree-of-freedom structure and the Newmark average-acceleration step
// (beta = 1/4, gamma = 1/2; Newmark 1959, Chopra "Dynamics of Structures" sec. 5.4),
// shared by the structure model and the controller's model of the structure.
#pragma once
#include <cmath>

namespace wsc {

struct Sdof {
  double m = 1, c = 0, k = 0;
  static Sdof from(double mass, double frequency_hz, double damping_ratio) {
    const double w = 2 * M_PI * frequency_hz;
    return {mass, 2 * damping_ratio * w * mass, w * w * mass};
  }
};

struct SdofState {
  double D = 0, V = 0, A = 0;
};

inline double newmark_effective_mass(const Sdof& s, double dt) { return s.m + 0.5 * dt * s.c + 0.25 * dt * dt * s.k; }

// The acceleration at the end of a step of length dt under force F (from the state at its start).
inline double newmark_acceleration(const Sdof& s, const SdofState& x0, double F, double dt) {
  const double rhs = F - s.c * (x0.V + 0.5 * dt * x0.A) - s.k * (x0.D + dt * x0.V + 0.25 * dt * dt * x0.A);
  return rhs / newmark_effective_mass(s, dt);
}

inline SdofState newmark_step(const Sdof& s, const SdofState& x0, double F, double dt) {
  SdofState x1;
  x1.A = newmark_acceleration(s, x0, F, dt);
  x1.V = x0.V + 0.5 * dt * (x0.A + x1.A);
  x1.D = x0.D + dt * x0.V + 0.25 * dt * dt * (x0.A + x1.A);
  return x1;
}

}  // namespace wsc
