#pragma once
// A string as one shell word for the tests that build command lines: in single quotes, each
// embedded ' written as '\'' (spaces and the like in a temporary or build folder stay part of
// the path).
#include <string>

namespace builtscene::testing {

inline std::string shell_quote(const std::string& s) {
  std::string r = "'";
  for (char c : s) r += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return r + "'";
}

}  // namespace builtscene::testing
