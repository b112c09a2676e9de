#include "io/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "core/errors.hpp"

namespace builtscene {

Trajectory read_tum_trajectory(const std::filesystem::path& path, bool require_nonempty) {
  std::ifstream in(path);
  if (!in) throw_input_error(path, 0, "cannot open trajectory file");
  Trajectory out;
  std::string line;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream ss(line);
    double v[8];
    for (int i = 0; i < 8; ++i) {
      if (!(ss >> v[i]))
        throw_input_error(path, line_no, "expected 8 numbers 'timestamp tx ty tz qx qy qz qw'");
      if (!std::isfinite(v[i])) throw_input_error(path, line_no, "value is not finite");
    }
    std::string extra;
    if (ss >> extra) throw_input_error(path, line_no, "more than 8 values on the line");
    Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    const double n = q.norm();
    if (std::abs(n - 1.0) > 1e-2) throw_input_error(path, line_no, "quaternion is not unit length (norm " + std::to_string(n) + ")");
    out.push_back({v[0], SE3(q, Eigen::Vector3d(v[1], v[2], v[3]))});
  }
  if (require_nonempty && out.empty()) throw_input_error(path, 0, "no poses in trajectory file");
  return out;
}

void write_tum_trajectory(const std::filesystem::path& path, const Trajectory& trajectory) {
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path);
  if (!out) throw Failure(located(path, 0, "cannot write trajectory file"));
  out << "# timestamp tx ty tz qx qy qz qw (camera in world)\n" << std::fixed;
  for (const auto& p : trajectory) {
    const auto& t = p.pose.translation();
    const auto& q = p.pose.rotation();
    out << std::setprecision(6) << p.timestamp << std::setprecision(9) << ' ' << t.x() << ' ' << t.y() << ' '
        << t.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << '\n';
  }
  if (!out) throw Failure(located(path, 0, "cannot write trajectory file"));
}

}  // namespace builtscene
