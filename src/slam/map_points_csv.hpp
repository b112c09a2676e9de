#pragma once
// The map's points with their provenance, as a CSV a user can analyse (or plot) outside the
// program: one row per (point, keyframe observing it).
//   point_id,x,y,z,observations,keyframe_timestamp,reference,u,v,level,depth
// x, y, z: the point in the map's world (metres); observations: keyframes that see it;
// keyframe_timestamp: the observing keyframe's; reference: 1 on the row of the point's
// reference keyframe; u, v: the keypoint there (undistorted pixels); level: its pyramid level;
// depth: that keyframe's depth reading at the keypoint (metres, 0 = none). Rows by point id,
// then keyframe id.
#include <filesystem>

namespace builtscene::slam {

class Map;

struct MapPointsCsvInfo {
  long points = 0, rows = 0;
};

// Takes the map's lock. Throws Failure naming the file when it cannot be written.
MapPointsCsvInfo write_map_points_csv(const Map& map, const std::filesystem::path& path);

}  // namespace builtscene::slam
