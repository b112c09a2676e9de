#pragma once
// The hybrid platform of the source's Figure 5.4: the sub-models of one model (a group in
// the scenario) exchange their `local` channels peer to peer over LCM UDP multicast, and
// everything between models goes through the mediator. A model's wrapper talks to one
// Transport; this one routes each channel to LCM or to the mediator and bridges a local
// channel to the mediator when someone outside the group (another model, the recorder)
// reads it. Model code and the wrapper do not change.
#include <memory>
#include <string>

#include "couple/model_config.hpp"
#include "couple/transport.hpp"

namespace builtscene::couple {

// The transport of model `model`'s wrapper: `url` (the mediator, or any transport) for
// every channel, plus its group's LCM for the scenario's local channels. Without local
// channels that concern the model this is just make_transport(url). `recorder`: the
// launcher records, so local channels are bridged to `url` as well.
std::unique_ptr<Transport> make_model_transport(const ScenarioConfig& scenario, const std::string& model,
                                                const std::string& url, bool recorder);

// Whether model `model` receives channel `channel` over its group's LCM (no history there,
// so it cannot resume from the mediator after a crash).
bool reads_locally(const ScenarioConfig& scenario, const std::string& model, const std::string& channel);

// Whether a local channel also goes to the mediator: a consumer outside the producer's
// group, or the recorder.
bool is_bridged(const ScenarioConfig& scenario, const std::string& channel, bool recorder);

}  // namespace builtscene::couple
