// The model function of 'wind': turbulent wind speed U(t) at the building and the
// quasi-steady drag force P(t) = 1/2 rho Cd A U(t)|U(t)| (README.md, equations 1-3).
#include "wind_model.hpp"

#include "../common/kaimal.hpp"

struct WindState {
  wsc::KaimalWind wind;
  wsc::SpectralSeries turbulence;
  double rho, cd, area, ramp;
};

WindState* wind_init(const nlohmann::json& p) {
  const wsc::KaimalWind w{p.at("mean_speed").get<double>(), p.at("height").get<double>(),
                          p.at("roughness").get<double>()};
  return new WindState{w,
                       wsc::SpectralSeries(w, p.at("frequencies").get<int>(), p.at("max_frequency").get<double>(),
                                           p.at("seed").get<uint64_t>()),
                       p.at("air_density").get<double>(), p.at("drag_coefficient").get<double>(),
                       p.at("area").get<double>(), p.value("ramp_time", 0.0)};
}

void wind_free(WindState* state) { delete state; }

void wind(WindState& state, int64_t step, double t,
    decltype(wsc::wind_t::U)& U,
    decltype(wsc::wind_t::P)& P) {
  (void)step;
  U = state.wind.mean + state.turbulence(t);
  // A smooth start (half cosine) so the structure is not hit by a sudden load.
  const double r = t < state.ramp ? 0.5 * (1 - std::cos(M_PI * t / state.ramp)) : 1.0;
  P = r * 0.5 * state.rho * state.cd * state.area * U * std::abs(U);
}
