#pragma once
// Runs the builtscene executable from a test and captures stdout, stderr and the exit code.
#include <sys/wait.h>

#include <unistd.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "shell_quote.hpp"

namespace builtscene::testing {

struct CliResult {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

// Runs a shell command line; stdout and stderr captured separately.
inline CliResult run_cli_command(const std::string& command_line) {
  // pid + call number: unique per process and per call (atomic: calls may come from threads).
  static std::atomic<unsigned> counter{0};
  const auto err_file = std::filesystem::temp_directory_path() /
                        ("builtscene_test_stderr_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  const std::string cmd = command_line + " 2>" + shell_quote(err_file.string());
  CliResult r;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf{};
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) r.out.append(buf.data(), n);
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  std::ifstream e(err_file);
  std::stringstream ss;
  ss << e.rdbuf();
  r.err = ss.str();
  std::filesystem::remove(err_file);
  return r;
}

// `args` is a shell-ready argument string for builtscene (quote paths with shell_quote).
inline CliResult run_cli(const std::string& args) { return run_cli_command(shell_quote(BUILTSCENE_BINARY) + " " + args); }

// Number of non-empty lines: error messages must be exactly one line.
inline int line_count(const std::string& s) {
  int lines = 0;
  std::istringstream in(s);
  std::string l;
  while (std::getline(in, l))
    if (!l.empty()) ++lines;
  return lines;
}

inline std::filesystem::path source_dir() { return BUILTSCENE_SOURCE_DIR; }
inline std::filesystem::path shared_data() { return source_dir() / ".." / "shared" / "data"; }

}  // namespace builtscene::testing
