#pragma once
// Plane landmarks (on by default; `--no-depth-planes` turns them off): the walls, floor and ceiling a keyframe's
// depth sees (depth_planes.hpp) become map landmarks shared by every keyframe that sees the
// same plane, and bundle adjustment holds each keyframe to its measured distance and tilt to
// them. Down a corridor whose walls carry no features, the map points sit on the far end
// wall, where a turn and a sideways slide look alike (docs/slam.md, "The depth prior"); a
// wall seen from every keyframe along the straight ties their headings and lateral
// positions together, so they cannot drift apart one keyframe at a time.
//
// Association (local mapping, under the map lock): a keyframe's measured plane, moved into
// the world with the keyframe's pose, joins the map plane whose normal is within match_deg,
// whose offset is within match_m and which was last seen from within match_range_m; else it
// starts a new one. Bundle adjustment refines the planes with the poses (local BA also holds
// up to `anchors` older observers of each local plane fixed, so the new keyframes are pulled
// to where the plane has been all along). A loop correction moves keyframes under their
// planes: refit_and_merge_planes() then re-estimates each plane from its observers and joins
// the planes of one wall that the drift had kept apart. Saved with the map (version 4).
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "core/se3.hpp"
#include "slam/depth_planes.hpp"
#include "slam/local_bundle_adjuster.hpp"

namespace builtscene::slam {

class KeyFrame;
class Map;

struct PlaneLandmarkOptions {
  bool enabled = true;  // on by default since 2026-12-05 (docs/slam.md, "Plane landmarks by default")
  double sigma_rad = 0.005;  // a measured plane's normal (0.29 degrees)
  double sigma_m = 0.01;     // its distance
  double match_deg = 5;
  double match_m = 0.08;
  double match_range_m = 8;
  int anchors = 8;
  DepthPlaneOptions extraction;
};

// A plane n_w.X + d_w = 0 in the world. Guarded by the map lock.
struct MapPlane {
  long id = 0;
  Eigen::Vector3d n_w = Eigen::Vector3d::UnitZ();
  double d_w = 0;
  Eigen::Vector3d last_seen_from = Eigen::Vector3d::Zero();  // centre of its newest observer
  std::vector<std::weak_ptr<KeyFrame>> observers;            // in the order they joined
};

// One plane a keyframe's depth measured, and the map plane it was associated with.
struct KeyFramePlane {
  PlaneMeasurement m;
  std::shared_ptr<MapPlane> landmark;
};

// A camera-frame plane moved into the world with the camera's pose T_cw.
PlaneMeasurement plane_in_world(const PlaneMeasurement& m_c, const SE3& T_cw);

// Associates the keyframe's measured planes (KeyFrame::planes) with the map's, making new
// map planes where none matches. Requires the map lock.
void associate_planes(KeyFrame& kf, Map& map, const PlaneLandmarkOptions& opt);

// Adds the plane measurements of the cameras in `cams` (pb.cameras in the same order) to
// `pb`, each plane started at the inlier-weighted mean of its measurements from those
// cameras; with anchors > 0 up to that many other observers of each plane are appended to
// `cams` and `pb.cameras` as fixed cameras. Free cameras that no chain of shared points (or
// depth links) joins to a fixed camera are also held loosely in place (the planes alone would
// leave them sliding along the walls): each at BundleAdjustmentProblem's hold sigmas, or with
// hold_groups_as_a_whole each group's common motion at those sigmas (global BA, where such a
// group can be most of the map). Returns the map planes in pb.planes' order.
// Requires the map lock.
std::vector<std::shared_ptr<MapPlane>> add_plane_terms(std::vector<std::shared_ptr<KeyFrame>>& cams,
                                                       BundleAdjustmentProblem& pb, const PlaneLandmarkOptions& opt,
                                                       int anchors, bool hold_groups_as_a_whole = false);

// After a loop correction moved keyframes (the pose graph; global BA with refit = false):
// with refit, each map plane is re-estimated as the inlier-weighted mean of its live observers'
// measurements at their current poses, and its last_seen_from is its newest observer's centre.
// Then planes of one surface are merged: normals within match_deg, offsets within match_m, and
// some observer of one within match_range_m of some observer of the other (a wall seen on two
// laps of a loop, which the drift had kept apart). The older plane absorbs the newer one's
// observers and keyframe measurements; without refit the merged plane is the two planes' mean
// weighted by observers. Returns the number of planes merged away. Requires the map lock.
int refit_and_merge_planes(Map& map, const PlaneLandmarkOptions& opt, bool refit = true);

// Writes bundle adjustment's solved planes (in add_plane_terms' order) back to the map planes.
// Requires the map lock.
void store_solved_planes(const std::vector<std::shared_ptr<MapPlane>>& planes,
                         const std::vector<BundleAdjustmentProblem::Plane>& solved);

}  // namespace builtscene::slam
