// The model function of 'controller': the active control force Pc(t). From the
// structure's state at the previous step and the wind force of this step it predicts the
// acceleration the Newmark step would give without control, A_free, and applies the force
// that brings it to the limit when it would exceed it (README.md, equation 7):
//   Pc = m_eff (clamp(A_free, -a_max, a_max) - A_free)
#include "controller_model.hpp"

#include <algorithm>

#include "../common/sdof.hpp"

struct ControllerState {
  wsc::Sdof sdof;
  double dt, limit;
  bool enabled;
};

ControllerState* controller_init(const nlohmann::json& p) {
  return new ControllerState{wsc::Sdof::from(p.at("mass").get<double>(), p.at("frequency").get<double>(),
                                             p.at("damping_ratio").get<double>()),
                             p.at("dt").get<double>(), p.at("acceleration_limit").get<double>(), p.value("enabled", true)};
}

void controller_free(ControllerState* state) { delete state; }

void controller(ControllerState& state, int64_t step, double t,
    const decltype(wsc::response_t::D)& D,
    const decltype(wsc::response_t::V)& V,
    const decltype(wsc::response_t::A)& A,
    const decltype(wsc::wind_t::U)& U,
    const decltype(wsc::wind_t::P)& P,
    decltype(wsc::control_t::Pc)& Pc) {
  (void)step;
  (void)t;
  (void)U;
  Pc = 0;
  if (!state.enabled) return;
  const double a_free = wsc::newmark_acceleration(state.sdof, {D, V, A}, P, state.dt);
  const double a_target = std::clamp(a_free, -state.limit, state.limit);
  Pc = wsc::newmark_effective_mass(state.sdof, state.dt) * (a_target - a_free);
}
