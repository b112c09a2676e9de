#pragma once
// Subcommands register themselves from their own source file (cmd_<name>.cpp), so adding a
// command never touches main.cpp:
//
//   static const bool registered = builtscene::app::register_command({
//       .path = {"eval", "ate"},
//       .description = "Absolute trajectory error",
//       .setup = [](CLI::App& cmd) -> builtscene::app::Action {
//         auto opt = std::make_shared<Options>();
//         cmd.add_option("--gt", opt->gt, "...")->required();
//         return [opt] { return run(*opt); };   // returns the JSON summary
//       }});
//
// Every leaf command gets `--json`: the summary the action returns is printed on stdout as
// one JSON object. Human text goes to stderr (spdlog). Exceptions map to exit codes:
// InputError and CLI11 parse errors -> 2, Failure and anything else -> 1.
#include <CLI/CLI.hpp>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace builtscene::app {

using Action = std::function<nlohmann::json()>;

struct Command {
  std::vector<std::string> path;  // e.g. {"synth", "rgbd"}; parents are created as needed
  std::string description;
  std::function<Action(CLI::App&)> setup;
  int order = 100;                // position in --help among siblings
};

bool register_command(Command command);

// Description of a parent group such as "synth" or "barcodes" (optional).
bool register_group(const std::string& name, const std::string& description);

// Builds the CLI from every registered command and runs it; returns the process exit code.
int run_cli(int argc, char** argv);

}  // namespace builtscene::app
