#pragma once
// A region on the map: an axis-aligned rectangle "x0,y0,x1,y1" or a polygon "x0,y0,x1,y1,x2,y2,...".
#include <string>
#include <vector>

#include <Eigen/Core>

namespace builtscene {

class Region {
 public:
  // Throws InputError naming `option` on a malformed list.
  static Region parse(const std::string& text, const std::string& option = "--region");
  static Region rectangle(double x0, double y0, double x1, double y1);
  explicit Region(std::vector<Eigen::Vector2d> polygon);

  bool contains(const Eigen::Vector2d& p) const;  // even-odd rule; boundary counts as inside
  const std::vector<Eigen::Vector2d>& polygon() const { return polygon_; }
  double area() const;

 private:
  std::vector<Eigen::Vector2d> polygon_;
};

}  // namespace builtscene
