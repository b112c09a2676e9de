#include "nav/region.hpp"

#include <cmath>
#include <sstream>

#include "core/errors.hpp"

namespace builtscene {

Region::Region(std::vector<Eigen::Vector2d> polygon) : polygon_(std::move(polygon)) {
  if (polygon_.size() < 3) throw InputError("region: a polygon needs at least 3 vertices");
}

Region Region::rectangle(double x0, double y0, double x1, double y1) {
  if (x0 > x1) std::swap(x0, x1);
  if (y0 > y1) std::swap(y0, y1);
  return Region({{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}});
}

Region Region::parse(const std::string& text, const std::string& option) {
  std::string s = text;
  for (char& c : s)
    if (c == ',' || c == ';') c = ' ';
  std::istringstream in(s);
  std::vector<double> v;
  double x;
  while (in >> x) {
    if (!std::isfinite(x)) throw InputError(option + ": values must be finite");
    v.push_back(x);
  }
  if (!in.eof()) throw InputError(option + ": expected numbers separated by commas, got '" + text + "'");
  if (v.size() == 4) {
    if (v[0] == v[2] || v[1] == v[3]) throw InputError(option + ": the rectangle has no area");
    return rectangle(v[0], v[1], v[2], v[3]);
  }
  if (v.size() < 6 || v.size() % 2) throw InputError(option + ": expected x0,y0,x1,y1 (a rectangle) or at least 3 x,y vertices");
  std::vector<Eigen::Vector2d> poly;
  for (std::size_t i = 0; i < v.size(); i += 2) poly.emplace_back(v[i], v[i + 1]);
  Region r(std::move(poly));
  if (r.area() <= 0) throw InputError(option + ": the polygon has no area");
  return r;
}

bool Region::contains(const Eigen::Vector2d& p) const {
  bool inside = false;
  const std::size_t n = polygon_.size();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const auto& a = polygon_[i];
    const auto& b = polygon_[j];
    // On the edge: inside.
    const Eigen::Vector2d ab = b - a, ap = p - a;
    const double cross = ab.x() * ap.y() - ab.y() * ap.x();
    if (std::abs(cross) < 1e-12 && ap.dot(ab) >= 0 && ap.dot(ab) <= ab.squaredNorm()) return true;
    if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x())
      inside = !inside;
  }
  return inside;
}

double Region::area() const {
  double s = 0;
  for (std::size_t i = 0, j = polygon_.size() - 1; i < polygon_.size(); j = i++)
    s += polygon_[j].x() * polygon_[i].y() - polygon_[i].x() * polygon_[j].y();
  return std::abs(s) / 2;
}

}  // namespace builtscene
