#pragma once
// The model-function prototype generator (the source's Figure 5.7): from a model config
// and its message definitions it writes a C++ stub named after the model, whose
// arguments are every input-message variable and whose results are every output-message
// variable, the glue that makes it a plugin for the wrapper, a CMake project that builds
// it (lcm-gen generates the message types at build time), and a Python stub for the
// JSON-lines protocol. The user fills in the body only.
#include <filesystem>
#include <string>
#include <vector>

#include "couple/model_config.hpp"

namespace builtscene::couple {

struct GeneratedStub {
  std::vector<std::filesystem::path> written;
  std::vector<std::filesystem::path> kept;  // user files that already existed
  std::string signature;                    // the C++ model function declaration
};

// `messages`: the .lcm files (the config's own `messages` are used when empty).
// Existing user files (NAME.cpp, NAME.py) are kept unless `overwrite`.
GeneratedStub generate_model_stub(const ModelConfig& config, std::vector<std::filesystem::path> messages,
                                  const std::filesystem::path& out_dir, bool overwrite = false);

}  // namespace builtscene::couple
