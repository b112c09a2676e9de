#pragma once
// The wrappers' status channel: every model reports its step, what it waits for and the
// oldest step it still needs of each input. Producers use it for flow control and for
// re-publishing lost outputs (the source's live-data rule); the launcher and `couple spy`
// use it to show progress and to name the model, channel and step of a stall. It is an
// LCM type like any other, so lcm-spy shows it too.
#include <cstdint>
#include <string>
#include <vector>

#include "couple/lcm_types.hpp"

namespace builtscene::couple {

inline constexpr const char* kStatusChannel = "BUILTSCENE_STATUS";
inline constexpr const char* kStatusType = "builtscene.status_t";
inline constexpr const char* kRecorderName = "(recorder)";

// Each model reports on its own channel BUILTSCENE_STATUS.MODEL (the launcher's recorder on
// the bare BUILTSCENE_STATUS), so a wrapper subscribes only to the statuses of the models it
// exchanges data with: when every wrapper heard every status, a run of N models cost
// O(N^2) deliveries and the mediator saturated at a few tens of models.
std::string status_channel(const std::string& model);
// Wall-clock time in microseconds since the epoch, the `utime` of statuses and log events.
int64_t now_us();
bool is_status_channel(const std::string& channel);

enum class ModelState : int8_t { kRunning = 0, kWaiting = 1, kDone = 2, kFailed = 3, kStopped = 4 };
const char* state_name(ModelState s);

struct ModelStatus {
  std::string model;
  int64_t step = 0;  // steps completed
  int64_t steps = 0;  // steps in the run
  int64_t utime = 0;
  ModelState state = ModelState::kRunning;
  std::vector<std::pair<std::string, int64_t>> waiting;  // channel, producer step
  std::vector<std::pair<std::string, int64_t>> needs;    // channel, oldest producer step still needed
  std::string error;
  // The time manager's grant: no message stamped earlier can still reach the model
  // (seconds; +inf for a model without inputs).
  double granted = 0;
  // Per event-driven output channel: events published stamped before `step` (the initial
  // publication at step -1 included), so a consumer knows when it has all of them.
  std::vector<std::pair<std::string, int64_t>> events;
};

// Adds builtscene.status_t to a registry.
void add_builtin_types(TypeRegistry& types);

std::vector<uint8_t> encode_status(const TypeRegistry& types, const ModelStatus& s);
ModelStatus decode_status(const TypeRegistry& types, const uint8_t* data, std::size_t size);

}  // namespace builtscene::couple
