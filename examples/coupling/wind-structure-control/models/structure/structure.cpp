// The model function of 'structure': one Newmark step of the SDOF building under the
// wind force plus the control force (README.md, equations 4-6). The previous state comes
// in as the STRUCTURE channel's previous step, so no hidden state is kept.
#include "structure_model.hpp"

#include "../common/sdof.hpp"

struct StructureState {
  wsc::Sdof sdof;
  double dt;
};

StructureState* structure_init(const nlohmann::json& p) {
  return new StructureState{wsc::Sdof::from(p.at("mass").get<double>(), p.at("frequency").get<double>(),
                                            p.at("damping_ratio").get<double>()),
                            p.at("dt").get<double>()};
}

void structure_free(StructureState* state) { delete state; }

void structure(StructureState& state, int64_t step, double t,
    const decltype(wsc::wind_t::U)& U,
    const decltype(wsc::wind_t::P)& P,
    const decltype(wsc::control_t::Pc)& Pc,
    const decltype(wsc::response_t::D)& structure_D,
    const decltype(wsc::response_t::V)& structure_V,
    const decltype(wsc::response_t::A)& structure_A,
    decltype(wsc::response_t::D)& D,
    decltype(wsc::response_t::V)& V,
    decltype(wsc::response_t::A)& A) {
  (void)step;
  (void)t;
  (void)U;
  const wsc::SdofState x = wsc::newmark_step(state.sdof, {structure_D, structure_V, structure_A}, P + Pc, state.dt);
  D = x.D;
  V = x.V;
  A = x.A;
}
