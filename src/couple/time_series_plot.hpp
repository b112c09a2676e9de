#pragma once
// PNG plots of time series: one panel per variable stacked vertically, several curves
// per panel (e.g. with and without control), optional horizontal limit lines.
#include <filesystem>
#include <string>
#include <vector>

namespace builtscene::couple {

struct Curve {
  std::string label;
  std::vector<double> x, y;
  int r = 0, g = 0, b = 0;
};

struct Panel {
  std::string title;  // e.g. "A(t) [m/s^2]"
  std::vector<Curve> curves;
  std::vector<double> limits;  // dashed horizontal lines
};

// Throws Failure when the file cannot be written.
void plot_panels(const std::vector<Panel>& panels, const std::string& x_label, const std::filesystem::path& png);

}  // namespace builtscene::couple
