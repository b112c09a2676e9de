#include "command_registry.hpp"

#include <algorithm>
#include <iostream>
#include <map>
#include <memory>

#include "core/errors.hpp"
#include "core/logging.hpp"
#include "slam/solver_logging.hpp"

#ifndef BUILTSCENE_VERSION
#define BUILTSCENE_VERSION "0.0.0"
#endif

namespace builtscene::app {
namespace {

std::vector<Command>& commands() {
  static std::vector<Command> list;
  return list;
}

std::map<std::string, std::string>& groups() {
  static std::map<std::string, std::string> map;
  return map;
}

// One line, no trailing newline: CLI11 messages can span lines.
std::string one_line(std::string s) {
  std::replace(s.begin(), s.end(), '\n', ' ');
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

}  // namespace

bool register_command(Command command) {
  commands().push_back(std::move(command));
  return true;
}

bool register_group(const std::string& name, const std::string& description) {
  groups()[name] = description;
  return true;
}

int run_cli(int argc, char** argv) {
  CLI::App app{"builtscene: scene understanding for the built environment"};
  app.set_version_flag("--version", std::string("builtscene ") + BUILTSCENE_VERSION);
  app.require_subcommand(1);
  int verbosity = 1;
  app.add_flag_function("-q,--quiet", [&](std::int64_t) { verbosity = 0; }, "Only warnings on stderr");
  app.add_flag_function("-v,--verbose", [&](std::int64_t) { verbosity = 2; }, "Debug messages on stderr");

  auto sorted = commands();
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const Command& a, const Command& b) { return a.order < b.order; });

  struct Leaf {
    CLI::App* cmd;
    Action action;
    bool json = false;
  };
  std::vector<std::unique_ptr<Leaf>> leaves;
  for (const auto& c : sorted) {
    CLI::App* parent = &app;
    for (std::size_t i = 0; i + 1 < c.path.size(); ++i) {
      CLI::App* sub = nullptr;
      try {
        sub = parent->get_subcommand(c.path[i]);
      } catch (const CLI::OptionNotFound&) {
        auto it = groups().find(c.path[i]);
        sub = parent->add_subcommand(c.path[i], it == groups().end() ? "" : it->second);
        sub->require_subcommand(1);
      }
      parent = sub;
    }
    auto leaf = std::make_unique<Leaf>();
    leaf->cmd = parent->add_subcommand(c.path.back(), c.description);
    leaf->cmd->add_flag("--json", leaf->json, "Print one JSON summary on stdout");
    leaf->action = c.setup(*leaf->cmd);
    leaves.push_back(std::move(leaf));
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "builtscene: " << one_line(e.what()) << " (see --help)\n";
    return 2;
  }

  init_logging(verbosity);
  slam::init_solver_logging(argc > 0 ? argv[0] : "builtscene", verbosity);
  for (auto& leaf : leaves) {
    if (!leaf->cmd->parsed()) continue;
    try {
      nlohmann::json summary = leaf->action();
      if (leaf->json) std::cout << summary.dump() << std::endl;
      return 0;
    } catch (const InputError& e) {
      std::cerr << "builtscene: " << one_line(e.what()) << "\n";
      return 2;
    } catch (const Failure& e) {
      std::cerr << "builtscene: " << one_line(e.what()) << "\n";
      return 1;
    } catch (const std::exception& e) {
      std::cerr << "builtscene: internal error: " << one_line(e.what()) << "\n";
      return 1;
    }
  }
  std::cerr << "builtscene: no command given (see --help)\n";
  return 2;
}

}  // namespace builtscene::app
