#include "core/errors.hpp"

namespace builtscene {

std::string located(const std::filesystem::path& file, std::size_t line, const std::string& message) {
  std::string s = file.string();
  if (line > 0) s += ":" + std::to_string(line);
  return s + ": " + message;
}

void throw_input_error(const std::filesystem::path& file, std::size_t line, const std::string& message) {
  throw InputError(located(file, line, message));
}

}  // namespace builtscene
