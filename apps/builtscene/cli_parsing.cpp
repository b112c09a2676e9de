#include "cli_parsing.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include "core/errors.hpp"

namespace builtscene::app {

Eigen::Vector2d parse_point2(const std::string& text, const std::string& option) {
  std::string s = text;
  for (char& c : s)
    if (c == ',') c = ' ';
  std::istringstream in(s);
  double x, y;
  std::string extra;
  if (!(in >> x >> y) || (in >> extra) || !std::isfinite(x) || !std::isfinite(y))
    throw InputError(option + ": expected X,Y in metres, got '" + text + "'");
  return {x, y};
}

void check_output_file(const std::filesystem::path& path) {
  if (path.empty()) return;
  std::ofstream probe(path, std::ios::app);
  if (!probe) throw InputError(located(path, 0, "cannot write output file"));
}

}  // namespace builtscene::app
