// builtscene: one command-line program over the libraries. Subcommands live in cmd_*.cpp
// and register themselves (see command_registry.hpp).
#include "command_registry.hpp"

int main(int argc, char** argv) { return builtscene::app::run_cli(argc, argv); }
