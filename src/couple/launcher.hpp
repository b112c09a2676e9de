#pragma once
// Runs a scenario: every model in its own process (udpm://) or thread (memq://), one
// wrapper each, while the launcher records every channel to an LCM log, shows each
// model's step, stops everything cleanly on Ctrl-C, and fails with a clear message when a
// model fails or exits, or when no model advances within the scenario's timeout (naming
// the model, the channel and the step it waits for). The log is kept in every case.
#include <atomic>
#include <filesystem>
#include <map>
#include <optional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "couple/model_config.hpp"

namespace builtscene::couple {

struct LaunchOptions {
  std::filesystem::path record;      // empty: no log
  std::filesystem::path executable;  // the builtscene binary (default /proc/self/exe)
  std::filesystem::path scenario_file;  // passed to model processes
  bool show_progress = true;
  // The mediator (transport `mediator`): empty starts a local nats-server for the run;
  // nats://HOST:PORT uses that server (and then applies to any scenario transport).
  std::string nats;
  // Fault injection: SIGKILL model M's process when it reaches step S (M, S); the launcher
  // restarts it and it resumes from the mediator's history. Needs the mediator.
  std::vector<std::pair<std::string, int64_t>> kills;
  // Several hosts: start only these models here (empty: all); the others run on other
  // hosts, each under its own `couple launch --only ...` against the same --nats server.
  // This launcher still watches every model's status and fails on a stall.
  std::vector<std::string> only;
  int64_t history_per_channel = 1000000;  // JetStream: messages kept per channel
  int max_restarts = 3;                   // per model
  // Processes (udpm, mediator): host this many consecutive models of the scenario per
  // process, one wrapper thread each (`--models-per-process`, scenario `models_per_process`).
  int models_per_process = 0;  // 0: the scenario's (default 1)
};

struct LaunchResult {
  int64_t steps = 0;  // the longest model's steps
  double seconds = 0;      // wall time, model start-up included
  double run_seconds = 0;  // from the moment every model reported to the end
  double steps_per_second = 0;  // steps / run_seconds
  int64_t logged_events = 0;
  std::map<std::string, int64_t> model_steps;
  std::string transport;            // the URL the models used
  double mediator_cpu_seconds = -1;  // CPU of the nats-server the launcher started (-1: none)
  std::map<std::string, int> restarts;  // models restarted after dying by a signal
  nlohmann::json to_json() const;
};

// Throws Failure (a model failed, exited, stalled, or the user interrupted) after
// stopping the other models and closing the log.
LaunchResult launch(const ScenarioConfig& scenario, const LaunchOptions& options);

// The body of one model process (`builtscene couple run-model`): returns the exit code.
// `transport` overrides the scenario's (the launcher passes its own).
// Several models: one wrapper thread each. kill_at: fault injection, model -> step.
int run_model_process(const std::filesystem::path& scenario_file, const std::vector<std::string>& models,
                      const std::string& transport = "", bool recorder = false, bool resume = false,
                      const std::map<std::string, int64_t>& kill_at = {});

// SIGINT/SIGTERM set this; wrappers and the launcher poll it.
std::atomic<bool>& stop_flag();
void install_stop_signals();

}  // namespace builtscene::couple
