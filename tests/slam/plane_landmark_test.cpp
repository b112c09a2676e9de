// TruePlane landmarks against constructed truth: planes found in a ray-cast corridor depth image,
// bundle adjustment holding cameras to the walls they measure, association across keyframes.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "../common/kinect_camera.hpp"
#include "core/so3.hpp"
#include "slam/depth_planes.hpp"
#include "slam/key_frame.hpp"
#include "slam/local_bundle_adjuster.hpp"
#include "slam/map.hpp"
#include "slam/plane_landmark.hpp"
#include "map_test_fixture.hpp"
#include "plane_depth_render.hpp"
#include "synthetic_scene.hpp"

namespace builtscene::slam {
namespace {

using builtscene::testing::kinect_camera;

struct TruePlane {
  Eigen::Vector3d n;  // unit; n.X + d = 0
  double d;
};

// Camera coordinates (x right, y down, z forward): a corridor 2 m wide and 2.6 m high along z,
// the camera 1 m above the floor, 0.3 m left of the middle; an end wall 6 m ahead. Each plane
// oriented towards the camera (d > 0).
std::vector<TruePlane> corridor_planes() {
  return {{{0, -1, 0}, 1.0},     // floor y = 1
          {{0, 1, 0}, 1.6},      // ceiling y = -1.6
          {{1, 0, 0}, 0.7},      // left wall x = -0.7
          {{-1, 0, 0}, 1.3},     // right wall x = 1.3
          {{0, 0, -1}, 6.0}};    // end wall z = 6
}

// The planes' depth seen from the origin (test::render_planes, the camera of kinect_camera()),
// with Gaussian noise of sigma on every pixel that hits a plane.
cv::Mat ray_cast(const std::vector<TruePlane>& planes, double sigma, unsigned seed) {
  std::vector<test::Plane> as_render;  // n.X + d = 0 is n.X = -d
  for (const auto& p : planes) as_render.push_back({p.n, -p.d});
  cv::Mat depth = test::render_planes(as_render, SE3());
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u)
      if (float& z = depth.at<float>(v, u); z > 0) z = static_cast<float>(z + noise(rng));
  return depth;
}

double angle_between_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180 / M_PI;
}

TEST(DepthPlanes, FindsTheCorridorsFloorWallsAndCeilingUnderNoise) {
  const PinholeCamera cam = kinect_camera();
  const auto truth = corridor_planes();
  const cv::Mat depth = ray_cast(truth, 0.005, 3);
  const auto found = extract_depth_planes(depth, cam.fx, cam.fy, cam.cx, cam.cy);
  // The ceiling (1.6 m above: in view only beyond 3.5 m) and the end wall at 6 m lie beyond
  // max_depth (4 m); the floor and both walls are found, each once.
  ASSERT_EQ(found.size(), 3u);
  for (std::size_t t : {0, 2, 3}) {
    int matches = 0;
    for (const auto& f : found)
      if (angle_between_deg(f.n_c, truth[t].n) < 1.0) {
        ++matches;
        EXPECT_LT(angle_between_deg(f.n_c, truth[t].n), 0.3) << "plane " << t;
        EXPECT_NEAR(f.d_c, truth[t].d, 0.005) << "plane " << t;
        EXPECT_GE(f.inliers, 600u);
      }
    EXPECT_EQ(matches, 1) << "plane " << t;
  }
}

TEST(DepthPlanes, NoneInAnEmptyOrWrongTypeImage) {
  const PinholeCamera cam = kinect_camera();
  EXPECT_TRUE(extract_depth_planes(cv::Mat(), cam.fx, cam.fy, cam.cx, cam.cy).empty());
  EXPECT_TRUE(extract_depth_planes(cv::Mat(480, 640, CV_16U, cv::Scalar(1000)), cam.fx, cam.fy, cam.cx, cam.cy).empty());
  EXPECT_TRUE(extract_depth_planes(cv::Mat(480, 640, CV_32F, cv::Scalar(0)), cam.fx, cam.fy, cam.cx, cam.cy).empty());
}

TEST(PlaneLandmark, WorldPlaneOfACameraPlaneHoldsItsPoints) {
  const SE3 T_cw(so3_exp(Eigen::Vector3d(0.1, -0.4, 0.2)), Eigen::Vector3d(0.5, -0.2, 1.0));
  const PlaneMeasurement m_c{Eigen::Vector3d(0.2, -0.9, 0.1).normalized(), 1.2, 1000};
  const PlaneMeasurement m_w = plane_in_world(m_c, T_cw);
  // Three points on the plane in camera coordinates, moved to the world.
  const Eigen::Vector3d a = -m_c.d_c * m_c.n_c;
  const Eigen::Vector3d e1 = m_c.n_c.unitOrthogonal(), e2 = m_c.n_c.cross(e1);
  for (const Eigen::Vector3d& pc : {a, Eigen::Vector3d(a + 2 * e1), Eigen::Vector3d(a - e1 + 3 * e2)}) {
    const Eigen::Vector3d pw = T_cw.inverse() * pc;
    EXPECT_NEAR(m_w.n_c.dot(pw) + m_w.d_c, 0.0, 1e-12);
  }
}

// Cameras 1 m apart down a corridor (world = the first camera), each seeing a handful of
// points on the end wall 15 m ahead and measuring the two side walls and the floor exactly.
// The far points leave a turn and a sideways slide alike; the walls do not.
struct CorridorBa {
  BundleAdjustmentProblem pb;
  std::vector<SE3> truth;
};

CorridorBa corridor_ba(bool with_planes, unsigned seed) {
  CorridorBa c;
  auto& pb = c.pb;
  pb.K = test::kinect();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  std::normal_distribution<double> pixel(0, 1.0);
  // World planes (camera 0 = world): left wall x = -0.7, right wall x = 1.3, floor y = 1.
  const std::vector<TruePlane> walls = {{{1, 0, 0}, 0.7}, {{-1, 0, 0}, 1.3}, {{0, -1, 0}, 1.0}};
  for (int i = 0; i < 8; ++i) {
    const double yaw = 0.01 * std::sin(i);  // a little wander
    c.truth.push_back(SE3(so3_exp(Eigen::Vector3d(0, yaw, 0)), Eigen::Vector3d(0.05 * std::cos(i), 0, -1.0 * i)));
    pb.cameras.push_back({i < 2 ? c.truth.back() : test::perturb(c.truth.back(), 0.02, 0.1, rng), i < 2});
  }
  for (int j = 0; j < 30; ++j) {
    const Eigen::Vector3d p(u(rng), 0.5 * u(rng), 15.0 + u(rng));
    pb.points.push_back(p + Eigen::Vector3d(0.1 * u(rng), 0.1 * u(rng), 0.3 * u(rng)));  // start off
    for (int i = 0; i < 8; ++i) {
      BundleAdjustmentProblem::Measurement m;
      m.camera = i;
      m.point = j;
      m.o.uv = test::project(pb.K, c.truth[static_cast<std::size_t>(i)] * p) + Eigen::Vector2d(pixel(rng), pixel(rng));
      m.o.inv_sigma2 = 1.0;
      pb.measurements.push_back(m);
    }
  }
  if (with_planes) {
    for (const auto& w : walls) pb.planes.push_back({w.n + Eigen::Vector3d(0.02, 0.02, 0.02), w.d + 0.05});  // start off
    for (int i = 0; i < 8; ++i)
      for (std::size_t k = 0; k < walls.size(); ++k) {
        // The world plane seen from camera i: n_c = R n, d_c = d - n_c.t.
        const SE3& T = c.truth[static_cast<std::size_t>(i)];
        PlaneMeasurement m;
        m.n_c = T.rotation_matrix() * walls[k].n;
        m.d_c = walls[k].d - m.n_c.dot(T.translation());
        m.inliers = 1000;
        pb.plane_measurements.push_back({i, static_cast<int>(k), m});
      }
  }
  return c;
}

// Across the corridor and in height: what the walls and the floor fix (along it, only the far
// points' parallax does, and poorly).
double worst_sideways_error(const CorridorBa& c, const BundleAdjustmentResult& r) {
  double worst = 0;
  for (std::size_t i = 0; i < c.truth.size(); ++i) {
    const Eigen::Vector3d e = r.poses[i].inverse().translation() - c.truth[i].inverse().translation();
    worst = std::max(worst, e.head<2>().norm());
  }
  return worst;
}

TEST(PlaneLandmark, BundleAdjustmentHoldsCamerasToTheWallsTheyMeasure) {
  for (unsigned seed = 1; seed <= 3; ++seed) {
    auto with = corridor_ba(true, seed), without = corridor_ba(false, seed);
    const auto rw = solve_bundle_adjustment(with.pb, {20, 20});
    const auto ro = solve_bundle_adjustment(without.pb, {20, 20});
    ASSERT_TRUE(rw.solved && ro.solved);
    double worst_rot = 0;
    for (std::size_t i = 0; i < with.truth.size(); ++i)
      worst_rot = std::max(worst_rot, test::rotation_error_deg(rw.poses[i], with.truth[i]));
    // Exact walls and floor: every camera within 1 cm (the terms' sigma) of the truth across the corridor and in
    // height, and within 0.2 degrees (the plane terms' sigma is 0.29; the far points' pixel
    // noise pulls against them), the planes within 5 mm and 0.05 degrees.
    EXPECT_LT(worst_sideways_error(with, rw), 0.01) << "seed " << seed;
    EXPECT_LT(worst_rot, 0.2) << "seed " << seed;
    const std::vector<TruePlane> walls = {{{1, 0, 0}, 0.7}, {{-1, 0, 0}, 1.3}, {{0, -1, 0}, 1.0}};
    for (std::size_t k = 0; k < walls.size(); ++k) {
      EXPECT_LT(angle_between_deg(rw.planes[k].n, walls[k].n), 0.05) << "seed " << seed << " plane " << k;
      EXPECT_NEAR(rw.planes[k].d, walls[k].d, 0.005) << "seed " << seed << " plane " << k;
    }
    // Without them the far points alone leave the slide: at least 10x the error.
    EXPECT_GT(worst_sideways_error(without, ro), 10 * worst_sideways_error(with, rw)) << "seed " << seed;
  }
}

// A keyframe (no features) at camera centre c looking along world +z, measuring the given
// world planes as its depth would.
std::shared_ptr<KeyFrame> keyframe_seeing(Map& map, const Eigen::Vector3d& c, const std::vector<TruePlane>& world) {
  auto f = std::make_shared<FrameFeatures>();
  f->ctx = test::kinect_context();
  build_feature_grid(*f);
  Frame frame(map.peek_next_keyframe_id(), 1.0, f);
  const SE3 T_cw(Eigen::Quaterniond::Identity(), -c);
  frame.set_pose(T_cw);
  auto kf = std::make_shared<KeyFrame>(map.next_keyframe_id(), frame);
  for (const auto& w : world) {
    PlaneMeasurement m;
    m.n_c = w.n;                     // no rotation
    m.d_c = w.d + w.n.dot(c);        // d_c = d_w - n_c.t with t = -c
    m.inliers = 1000;
    kf->planes.push_back({m, nullptr});
  }
  map.add_keyframe(kf);
  return kf;
}

// World planes of the association tests (keyframes look along +z): the corridor's walls and
// floor, and a cabinet 10 cm in front of the left wall (not the wall).
const TruePlane kLeftWall{{1, 0, 0}, 0.7}, kRightWall{{-1, 0, 0}, 1.3}, kFloor{{0, -1, 0}, 1.0};
const TruePlane kCabinet{{1, 0, 0}, 0.6};

// n keyframes 0.5 m apart down the corridor, each seeing `wall` and associated in turn.
std::vector<std::shared_ptr<KeyFrame>> keyframes_along(Map& map, const PlaneLandmarkOptions& opt, const TruePlane& wall,
                                                       int n) {
  std::vector<std::shared_ptr<KeyFrame>> kfs;
  for (int i = 0; i < n; ++i) {
    kfs.push_back(keyframe_seeing(map, {0, 0, 0.5 * i}, {wall}));
    associate_planes(*kfs.back(), map, opt);
  }
  return kfs;
}

TEST(PlaneLandmark, AssociationJoinsOneWallAcrossKeyframesAndKeepsOthersApart) {
  Map map;
  std::lock_guard lock(map.mutex());
  PlaneLandmarkOptions opt;
  opt.enabled = true;
  const TruePlane &left = kLeftWall, &right = kRightWall, &floor = kFloor, &cabinet = kCabinet;
  auto a = keyframe_seeing(map, {0, 0, 0}, {left, right, floor});
  auto b = keyframe_seeing(map, {0.02, 0.01, 2.0}, {left, floor, cabinet});
  auto far = keyframe_seeing(map, {0, 0, 20.0}, {left});  // the same plane, but 18 m from its last sighting
  associate_planes(*a, map, opt);
  associate_planes(*b, map, opt);
  associate_planes(*far, map, opt);
  ASSERT_EQ(map.planes().size(), 5u);  // left, right, floor, cabinet, left again far away
  EXPECT_EQ(b->planes[0].landmark, a->planes[0].landmark);  // left wall
  EXPECT_EQ(b->planes[1].landmark, a->planes[2].landmark);  // floor
  EXPECT_NE(b->planes[2].landmark, a->planes[0].landmark);  // the cabinet is its own plane
  EXPECT_NE(far->planes[0].landmark, a->planes[0].landmark);
  // The world planes are the truth (the measurements are exact).
  const auto& wall = *a->planes[0].landmark;
  EXPECT_LT(angle_between_deg(wall.n_w, left.n), 1e-9);
  EXPECT_NEAR(wall.d_w, left.d, 1e-12);
  EXPECT_EQ(wall.observers.size(), 2u);
}

TEST(PlaneLandmark, BundleAdjustmentTermsComeWithAnchorsAndHoldLoneCamerasInPlace) {
  Map map;
  std::lock_guard lock(map.mutex());
  PlaneLandmarkOptions opt;
  opt.enabled = true;
  const TruePlane& left = kLeftWall;
  const auto kfs = keyframes_along(map, opt, left, 12);
  // A local problem of the newest keyframe alone, with no point seen by a fixed camera: the
  // wall comes with opt.anchors older observers (fixed), and the keyframe is held in place.
  BundleAdjustmentProblem pb;
  std::vector<std::shared_ptr<KeyFrame>> cams = {kfs.back()};
  pb.cameras.push_back({kfs.back()->pose(), false});
  const auto planes = add_plane_terms(cams, pb, opt, opt.anchors);
  ASSERT_EQ(planes.size(), 1u);
  EXPECT_EQ(cams.size(), 1u + static_cast<std::size_t>(opt.anchors));
  EXPECT_EQ(pb.plane_measurements.size(), cams.size());
  EXPECT_EQ(cams[1], kfs.front());  // the oldest observer is one of the anchors
  for (std::size_t c = 1; c < cams.size(); ++c) EXPECT_TRUE(pb.cameras[c].fixed);
  ASSERT_EQ(pb.held_in_place.size(), 1u);
  EXPECT_EQ(pb.held_in_place[0], (BundleAdjustmentProblem::Held{0, 1}));
  EXPECT_NEAR(pb.planes[0].d, left.d, 1e-12);
  // Off: nothing added.
  BundleAdjustmentProblem off;
  std::vector<std::shared_ptr<KeyFrame>> cams_off = {kfs.back()};
  off.cameras.push_back({kfs.back()->pose(), false});
  PlaneLandmarkOptions no_planes;
  no_planes.enabled = false;
  EXPECT_TRUE(add_plane_terms(cams_off, off, no_planes, 8).empty());
  EXPECT_TRUE(off.plane_measurements.empty());
}


// Global BA after a loop closure met a group of keyframes that shares no point with the rest
// (made just after the depth-odometry bridge, whose own keyframes are left out): only the
// walls tied it to the map, and walls leave the motion along them free. In the office world
// such a group slid 1.4-4 m down the corridor (docs/slam.md, "Plane landmarks by default, and
// groups without a shared point"). Here: group A (its first camera fixed) and group B see their own
// points and the same three planes; the right wall converges by 3 degrees and B's depth puts
// it 2 cm off, which B could explain only by sliding 0.38 m along the corridor.
TEST(PlaneLandmark, AGroupSharingNoPointWithTheFixedCamerasDoesNotSlideAlongTheWalls) {
  Map map;
  std::lock_guard lock(map.mutex());
  PlaneLandmarkOptions opt;
  opt.enabled = true;
  const double a = 3 * M_PI / 180;
  const TruePlane left{{1, 0, 0}, 0.7}, floor{{0, -1, 0}, 1.0};
  const TruePlane right{{-std::cos(a), 0, -std::sin(a)}, 1.3 * std::cos(a)};  // through (1.3, 0, 0)
  const TruePlane right_off{right.n, right.d + 0.02};
  std::vector<std::shared_ptr<KeyFrame>> cams;
  std::vector<Eigen::Vector3d> centres;
  for (int i = 0; i < 4; ++i) centres.push_back({0, 0, 0.5 * i});        // group A
  for (int i = 0; i < 3; ++i) centres.push_back({0, 0, 4.0 + 0.5 * i});  // group B
  BundleAdjustmentProblem pb;
  pb.K = test::kinect();
  for (std::size_t i = 0; i < centres.size(); ++i) {
    cams.push_back(keyframe_seeing(map, centres[i], {left, floor, i < 4 ? right : right_off}));
    associate_planes(*cams.back(), map, opt);
    pb.cameras.push_back({cams.back()->pose(), i == 0});
  }
  ASSERT_EQ(map.planes().size(), 3u);  // B's right wall is the same landmark, 2 cm off
  // Each group's own points 3-4 m ahead, every one seen (with depth) by every camera of its group.
  for (int g = 0; g < 2; ++g)
    for (int j = 0; j < 8; ++j) {
      const Eigen::Vector3d p(-0.5 + 0.15 * j, -0.3 + 0.1 * (j % 3), g == 0 ? 4.5 : 8.0);
      pb.points.push_back(p);
      for (std::size_t i = g == 0 ? 0 : 4; i < (g == 0 ? 4u : centres.size()); ++i) {
        BundleAdjustmentProblem::Measurement m;
        m.camera = static_cast<int>(i);
        m.point = static_cast<int>(pb.points.size()) - 1;
        const Eigen::Vector3d pc = cams[i]->pose() * p;
        m.o.uv = test::project(pb.K, pc);
        m.o.u_right = m.o.uv.x() - pb.K.bf / pc.z();
        pb.measurements.push_back(m);
      }
    }
  add_plane_terms(cams, pb, opt, 0, /*hold_groups_as_a_whole=*/true);
  // B's cameras, and only they, are held near where tracking put them, as one group.
  EXPECT_EQ(pb.held_in_place, (std::vector<BundleAdjustmentProblem::Held>{{4, 3}, {5, 3}, {6, 3}}));
  const auto r = solve_bundle_adjustment(pb, {20, 20});
  ASSERT_TRUE(r.solved);
  for (std::size_t i = 0; i < centres.size(); ++i) {
    const double moved = (r.poses[i].inverse().translation() - centres[i]).norm();
    EXPECT_LT(moved, 0.05) << "camera " << i;  // without the hold B slides ~0.38 m
  }
}

// A loop around a corridor: lap 1's keyframes were associated while drifted by a rigid D1 (their
// walls went into the map moved by D1), lap 2's at the same places while drifted by D2 (0.3 m
// sideways and 0.2 m in height: too far from lap 1's walls, so each wall got a second plane).
// The loop correction puts every keyframe back at its true pose; the planes must follow: each
// wall one plane again, at the truth, with both laps' keyframes as observers.
TEST(PlaneLandmark, ALoopCorrectionRefitsThePlanesAndJoinsEachWallsTwoLaps) {
  Map map;
  std::lock_guard lock(map.mutex());
  PlaneLandmarkOptions opt;
  opt.enabled = true;
  const TruePlane &left = kLeftWall, &right = kRightWall, &floor = kFloor, &cabinet = kCabinet;  // cabinet: lap 2 only
  const SE3 d1(so3_exp(Eigen::Vector3d(0, 1.0 * M_PI / 180, 0)), Eigen::Vector3d(0, 0.05, 0));
  const SE3 d2(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.3, 0.2, 0));
  std::vector<std::shared_ptr<KeyFrame>> lap1, lap2;
  // Measured from the true centre, tracked at drift * truth (camera -> world).
  auto drifted = [&](const Eigen::Vector3d& c, const std::vector<TruePlane>& seen, const SE3& drift) {
    auto kf = keyframe_seeing(map, c, seen);
    kf->set_pose((drift * kf->pose().inverse()).inverse());
    associate_planes(*kf, map, opt);
    return kf;
  };
  for (int i = 0; i < 12; ++i) lap1.push_back(drifted({0, 0, 0.5 * i}, {left, right, floor}, d1));
  for (int i = 0; i < 12; ++i) lap2.push_back(drifted({0, 0, 0.5 * i}, {left, right, floor, cabinet}, d2));
  // The same left wall 20 m further on, seen by one keyframe only, more than match_range_m from
  // every other observer: a plane of its own, before and after.
  auto far = drifted({0, 0, 20.0}, {left}, SE3());
  ASSERT_EQ(map.planes().size(), 8u);  // 3 per lap, the cabinet, the far wall
  ASSERT_NE(lap2[0]->planes[0].landmark, lap1[0]->planes[0].landmark);

  // The correction: every keyframe back at its true pose.
  for (int i = 0; i < 12; ++i)
    for (auto* lap : {&lap1, &lap2})
      (*lap)[static_cast<std::size_t>(i)]->set_pose(SE3(Eigen::Quaterniond::Identity(), -Eigen::Vector3d(0, 0, 0.5 * i)));

  EXPECT_EQ(refit_and_merge_planes(map, opt), 3);
  ASSERT_EQ(map.planes().size(), 5u);
  const std::vector<TruePlane> walls = {left, right, floor};
  for (std::size_t k = 0; k < walls.size(); ++k) {
    const auto& plane = lap1[0]->planes[k].landmark;
    for (std::size_t i = 0; i < 12; ++i) {
      EXPECT_EQ(lap1[i]->planes[k].landmark, plane) << "wall " << k << " lap 1 keyframe " << i;
      EXPECT_EQ(lap2[i]->planes[k].landmark, plane) << "wall " << k << " lap 2 keyframe " << i;
    }
    EXPECT_LT(angle_between_deg(plane->n_w, walls[k].n), 1e-6) << "wall " << k;
    EXPECT_NEAR(plane->d_w, walls[k].d, 1e-9) << "wall " << k;
    EXPECT_EQ(plane->observers.size(), 24u) << "wall " << k;
    // The newest observer (lap 2, 5.5 m down the corridor) is where the plane was last seen.
    EXPECT_LT((plane->last_seen_from - Eigen::Vector3d(0, 0, 5.5)).norm(), 1e-9) << "wall " << k;
  }
  const auto& cab = lap2[0]->planes[3].landmark;
  EXPECT_NE(cab, lap1[0]->planes[0].landmark);
  EXPECT_NEAR(cab->d_w, cabinet.d, 1e-9);
  EXPECT_NE(far->planes[0].landmark, lap1[0]->planes[0].landmark);
  // Nothing left to merge: a second call changes nothing.
  EXPECT_EQ(refit_and_merge_planes(map, opt), 0);
  EXPECT_EQ(map.planes().size(), 5u);
}

// Global BA's own planes are kept (no refit); two that coincide are joined at their mean
// weighted by observers.
TEST(PlaneLandmark, MergingWithoutRefitTakesTheObserverWeightedMean) {
  Map map;
  std::lock_guard lock(map.mutex());
  PlaneLandmarkOptions opt;
  opt.enabled = true;
  keyframes_along(map, opt, kLeftWall, 4);
  ASSERT_EQ(map.planes().size(), 1u);
  // A second plane of the same wall (as a drifted lap would have made), observed by one keyframe.
  auto extra = keyframe_seeing(map, {0, 0, 1.0}, {kLeftWall});
  auto second = std::make_shared<MapPlane>();
  second->id = map.next_plane_id();
  second->n_w = Eigen::Vector3d(1, 0, 0);
  second->d_w = 0.74;
  second->observers.push_back(extra);
  extra->planes[0].landmark = second;
  map.add_plane(second);
  map.planes()[0]->d_w = 0.70;
  EXPECT_EQ(refit_and_merge_planes(map, opt, /*refit=*/false), 1);
  ASSERT_EQ(map.planes().size(), 1u);
  EXPECT_NEAR(map.planes()[0]->d_w, (4 * 0.70 + 1 * 0.74) / 5, 1e-12);
  EXPECT_EQ(extra->planes[0].landmark, map.planes()[0]);
  EXPECT_EQ(map.planes()[0]->observers.size(), 5u);
}

}  // namespace
}  // namespace builtscene::slam
