#pragma once
// The message wrapper (the source's Figure 5.8, made robust): it subscribes to the
// model's input channels, decodes the step stamp of each message, buffers messages that
// arrive early, calls the model function when every expected input of the step is there
// (ratios, lags and history applied), publishes the outputs stamped with the step, and
// reports its status. It never busy-waits: it blocks in the transport until a message
// arrives. Producers keep their recent outputs until every consumer has moved past them
// and re-publish a step a consumer reports waiting for (lossy UDP), and they stay at
// most `window` steps ahead of their slowest consumer so no queue grows without bound.
#include <atomic>
#include <functional>
#include <memory>
#include <string>

#include "couple/model_config.hpp"
#include "couple/model_function.hpp"
#include "couple/status.hpp"
#include "couple/transport.hpp"

namespace builtscene::couple {

struct WrapperOptions {
  int window = 256;       // producer steps a producer may run ahead of a consumer's need
  int status_every = 32;  // steps between status reports while running
  int republish_ms = 10;  // minimum interval between re-publishing to a waiting consumer
  // After the last step, serve each consumer until it confirms, or until it has been
  // silent this long (it died); one that keeps reporting is served however long it takes.
  double linger_seconds = 10;
  const std::atomic<bool>* stop = nullptr;
  // The launcher records the run: treat its recorder (status name kRecorderName) as a
  // consumer of every output, so lost messages are re-sent to it too.
  bool recorder = false;
  // Recovery: a restarted model re-runs from step 0 on its inputs' history (the
  // transport must keep it) and publishes only the steps it had not published before.
  bool resume = false;
  // Fault injection (`couple launch --kill MODEL@STEP`): SIGKILL this process when it
  // reaches this step (before computing it); -1: never.
  int64_t kill_at = -1;
  // Called after each step with the step's outputs (used by tests and the monolithic check).
  std::function<void(int64_t step)> on_step;
};

class MessageWrapper {
 public:
  MessageWrapper(const ScenarioConfig& scenario, const std::string& model, Transport& transport,
                 std::unique_ptr<ModelFunction> function, WrapperOptions options = {});
  ~MessageWrapper();
  MessageWrapper(const MessageWrapper&) = delete;
  MessageWrapper& operator=(const MessageWrapper&) = delete;

  // Runs every step; returns when done and consumers are served, or when stopped (then
  // stopped() is true). Throws Failure when the model function fails (status "failed"
  // is published first).
  void run();
  bool stopped() const;
  int64_t steps_done() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace builtscene::couple
