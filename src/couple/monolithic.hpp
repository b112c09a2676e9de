#pragma once
// The monolithic reference: the scenario's model functions called in one loop, in a
// schedule that respects their dependencies, with no transport and no wrapper. The
// distributed run must produce the same numbers (tests/couple).
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "couple/model_config.hpp"

namespace builtscene::couple {

// channel -> decoded messages by step (initial publications at step -1 included).
using ChannelRecords = std::map<std::string, std::map<int64_t, nlohmann::json>>;

ChannelRecords run_monolithic(const ScenarioConfig& scenario);

}  // namespace builtscene::couple
