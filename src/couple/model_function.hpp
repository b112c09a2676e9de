#pragma once
// A model function as the wrapper sees it: LCM-encoded input messages in, LCM-encoded
// output messages out. Two kinds: a plugin (shared library from a generated C++ stub,
// loaded with dlopen) and an external program in any language speaking JSON lines.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "couple/model_config.hpp"

namespace builtscene::couple {

using Bytes = std::vector<uint8_t>;

class ModelFunction {
 public:
  virtual ~ModelFunction() = default;
  // inputs: per subscription in config order, `history` messages newest first.
  // outputs: resized to the number of publications; each must be filled (the step member
  // is stamped by the wrapper). Throws Failure with the model's own message on error.
  virtual void step(int64_t n, double t, const std::vector<std::vector<const Bytes*>>& inputs,
                    std::vector<Bytes>& outputs) = 0;
  // Checkpoints (optional hooks of the generated prototype): the model's state as bytes,
  // and back. Throw Failure on error.
  virtual bool can_checkpoint() const { return false; }
  virtual Bytes save() { return {}; }
  virtual void load(const Bytes& /*state*/) {}
};

// Loads the model named by the config (plugin or command). Plugins are searched as given,
// then relative to the config file, then in BUILTSCENE_PLUGIN_PATH and the build's plugin
// folder, as NAME, libNAME.so or NAME.so.
std::unique_ptr<ModelFunction> load_model_function(const ModelConfig& config, const TypeRegistry& types);

std::filesystem::path find_plugin(const ModelConfig& config);

}  // namespace builtscene::couple
