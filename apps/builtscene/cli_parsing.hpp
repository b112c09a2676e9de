#pragma once
// Small helpers shared by commands: parsers for values CLI11 does not know, output checks.
#include <Eigen/Core>
#include <filesystem>
#include <string>

namespace builtscene::app {

// "X,Y" -> point; InputError naming `option` otherwise.
Eigen::Vector2d parse_point2(const std::string& text, const std::string& option);

// Fails with a one-line InputError naming `path` when the output file cannot be written,
// before a command spends minutes on its input. An empty path (output not asked for) passes;
// an existing file is kept as it is (opened for appending).
void check_output_file(const std::filesystem::path& path);

}  // namespace builtscene::app
