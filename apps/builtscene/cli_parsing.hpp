#pragma once
// Small parsers shared by commands for values CLI11 does not know.
#include <Eigen/Core>
#include <string>

namespace builtscene::app {

// "X,Y" -> point; InputError naming `option` otherwise.
Eigen::Vector2d parse_point2(const std::string& text, const std::string& option);

}  // namespace builtscene::app
