#pragma once
// Model and scenario configuration (YAML). A model config is the "model configuration
// file" of the source's Figure 5.7: name, time step, end time, subscribed and published
// channels, time-step ratios, history, initial data. A scenario lists model configs and
// the transport. Every validation error names the file, line and field.
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "couple/lcm_types.hpp"

namespace builtscene::couple {

struct Subscription {
  std::string channel;
  std::string type;
  // The input's producer advances once per `every` of our steps, or `substeps` times per
  // one of ours (exactly one of them is > 1, or both are 1).
  int every = 1;
  int substeps = 1;
  int history = 1;  // how many of the latest producer steps the model function receives
  int lag = 0;      // producer steps behind the aligned one (1 breaks a same-step cycle)
  std::optional<nlohmann::json> initial;  // values for producer steps before 0
  std::size_t line = 0;

  // The producer step this model needs at its own step n (newest of the history).
  int64_t expected_step(int64_t n) const {
    const int64_t aligned = substeps > 1 ? (n + 1) * substeps - 1 : (n >= 0 ? n / every : -((-n + every - 1) / every));
    return aligned - lag;
  }
};

struct Publication {
  std::string channel;
  std::string type;
  std::optional<nlohmann::json> initial;  // published once, stamped step -1, before step 0
  // Event-driven: a step may publish nothing on this channel (the model leaves the output
  // empty). Consumers hold the newest event up to the step they need (sample-and-hold) and
  // learn from the producer's status that they have every event up to a step.
  bool events = false;
  std::size_t line = 0;
};

struct ModelConfig {
  std::filesystem::path file;
  std::string name;
  double dt = 0;
  double end_time = 0;
  int64_t steps() const;  // round(end_time / dt)
  // The model's promise (HLA lookahead): its outputs of time t take effect at t + lookahead
  // at the earliest; the time manager adds it to every message's time stamp.
  double lookahead = 0;
  // Recovery: save the model's state (the prototype's optional save/load hooks) to the
  // mediator every this many steps; a restarted model resumes from the last one. 0: never.
  int64_t checkpoint_every = 0;
  std::string plugin;                  // shared library (name or path) built from a generated stub
  std::vector<std::string> command;    // or: an external program speaking JSON lines
  nlohmann::json parameters = nlohmann::json::object();
  std::vector<std::filesystem::path> messages;  // .lcm files (resolved)
  std::vector<Subscription> subscribe;
  std::vector<Publication> publish;
  std::string transport;  // empty: the scenario's
  // Set by the scenario (models[i].group): the sub-models of one model share a group,
  // and the scenario's local channels travel between them over LCM.
  std::string group;
};

struct ScenarioConfig {
  std::filesystem::path file;
  std::string name;
  std::string transport = "udpm://239.255.76.67:7667?ttl=0";
  double timeout_seconds = 10;  // no model advancing for this long fails the run
  // `couple launch` over processes: consecutive models hosted per process (one wrapper
  // thread each), so a scenario of hundreds of models runs on a small machine.
  int models_per_process = 1;
  std::vector<std::filesystem::path> messages;
  std::vector<ModelConfig> models;
  TypeRegistry types;  // every .lcm file of the scenario and its models
  // The hybrid platform (the source's Figure 5.4): these channels (-> line in the file)
  // travel over LCM between the sub-models of their producer's group; every other
  // channel, and a local one's copy for consumers outside the group, goes through
  // `transport` (the mediator).
  std::map<std::string, std::size_t> local_channels;
  std::string local_transport = "udpm://239.255.76.67:7668?ttl=0";
  std::vector<std::string> groups;  // in order of first appearance

  const ModelConfig& model(const std::string& name) const;  // throws InputError
  bool is_local(const std::string& channel) const { return local_channels.count(channel) > 0; }
  // The LCM URL of a group: local_transport with its port + the group's index (each group
  // its own multicast port, so no process receives another building's datagrams).
  std::string local_url(const std::string& group) const;
};

// The mediator subject that keeps a model's checkpoints (in the run's history stream).
inline std::string checkpoint_channel(const std::string& model) { return "BUILTSCENE_CHECKPOINT." + model; }

// The name of the field in each message type that carries the producer's step.
inline constexpr const char* kStepField = "step";

ModelConfig load_model_config(const std::filesystem::path& file);

// Loads the scenario and its models, parses their messages and validates the whole
// coupling: known types with an int64_t `step`, one type per channel, one producer per
// channel, every subscribed channel produced, consistent time steps, initial values
// that encode, and no cycle that would deadlock (same-step cycles, or needing steps
// before 0 that nobody provides). Throws InputError.
ScenarioConfig load_scenario(const std::filesystem::path& file);

// The checks of load_scenario on an already loaded set of models (used by tests).
void validate_scenario(ScenarioConfig& scenario);

}  // namespace builtscene::couple
