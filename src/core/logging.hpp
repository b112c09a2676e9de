#pragma once
// Human-readable messages go to stderr through spdlog; stdout is reserved for --json output.
#include <spdlog/spdlog.h>

namespace builtscene {

// Installs the stderr logger. verbosity: 0 = warnings, 1 = info (default), 2 = debug.
void init_logging(int verbosity);

}  // namespace builtscene
