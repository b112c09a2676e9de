#pragma once
// Error kinds shared by every module. The CLI maps them to exit codes:
// InputError -> 2 (bad usage or bad input), Failure -> 1 (the work itself failed).
// Messages are one line and name the file, line or field at fault.
#include <filesystem>
#include <stdexcept>
#include <string>

namespace builtscene {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Failure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// "FILE: message" or "FILE:LINE: message" (line counted from 1; 0 omits it).
std::string located(const std::filesystem::path& file, std::size_t line, const std::string& message);

[[noreturn]] void throw_input_error(const std::filesystem::path& file, std::size_t line,
                                    const std::string& message);

}  // namespace builtscene
