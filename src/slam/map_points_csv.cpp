#include "slam/map_points_csv.hpp"

#include <fstream>
#include <mutex>

#include <fmt/format.h>

#include "core/errors.hpp"
#include "slam/key_frame.hpp"
#include "slam/map.hpp"
#include "slam/map_point.hpp"

namespace builtscene::slam {

MapPointsCsvInfo write_map_points_csv(const Map& map, const std::filesystem::path& path) {
  std::ofstream out(path);
  if (!out) throw Failure(located(path, 0, "cannot write map points"));
  out << "point_id,x,y,z,observations,keyframe_timestamp,reference,u,v,level,depth\n";
  MapPointsCsvInfo info;
  std::lock_guard lock(map.mutex());
  for (const auto& p : map.points()) {
    if (p->bad) continue;
    ++info.points;
    for (const auto& [kf, index] : p->observations) {
      const auto i = static_cast<std::size_t>(index);
      const cv::KeyPoint& k = kf->f->keys_un[i];
      const float depth = kf->f->depth[i] > 0 ? kf->f->depth[i] : 0.f;
      out << fmt::format("{},{:.6f},{:.6f},{:.6f},{},{:.6f},{},{:.3f},{:.3f},{},{:.4f}\n", p->id, p->position.x(),
                         p->position.y(), p->position.z(), p->observation_count(), kf->timestamp,
                         kf == p->reference ? 1 : 0, k.pt.x, k.pt.y, k.octave, depth);
      ++info.rows;
    }
  }
  out.flush();
  if (!out) throw Failure(located(path, 0, "cannot write map points"));
  return info;
}

}  // namespace builtscene::slam
