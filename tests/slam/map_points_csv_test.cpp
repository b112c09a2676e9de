// `slam --map-points-out`: every good map point appears once per observing keyframe, with its
// position, the keyframe's keypoint and depth reading, and exactly one reference row; a bad
// point does not appear. Checked against the map the fixture built.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "../common/scratch_dir.hpp"
#include "core/errors.hpp"
#include "map_test_fixture.hpp"
#include "slam/map_points_csv.hpp"

namespace builtscene::slam {
namespace {

TEST(MapPointsCsv, OneRowPerObservationWithTheKeyframesKeypointAndDepth) {
  const auto ctx = test::kinect_context();
  Map map;
  std::shared_ptr<MapPoint> retired;
  {
    std::lock_guard lock(map.mutex());
    test::build_random_map(map, ctx, 6, 40);
    retired = map.points().front();
    retired->set_bad(map);
  }
  const auto path = testing::scratch_dir("map_points") / "bs_map_points.csv";
  const auto info = write_map_points_csv(map, path);

  std::map<long, std::shared_ptr<MapPoint>> by_id;
  std::map<double, std::shared_ptr<KeyFrame>> kf_by_time;
  for (const auto& p : map.points())
    if (!p->bad) by_id[p->id] = p;
  for (const auto& kf : map.keyframes()) kf_by_time[kf->timestamp] = kf;

  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "point_id,x,y,z,observations,keyframe_timestamp,reference,u,v,level,depth");
  std::map<long, int> rows, references;
  long n = 0;
  while (std::getline(in, line)) {
    ++n;
    std::istringstream s(line);
    std::vector<double> v;
    for (std::string cell; std::getline(s, cell, ',');) v.push_back(std::stod(cell));
    ASSERT_EQ(v.size(), 11u) << line;
    const long id = static_cast<long>(v[0]);
    ASSERT_TRUE(by_id.count(id)) << "unknown or retired point " << id;
    const auto& p = by_id[id];
    EXPECT_NEAR(v[1], p->position.x(), 1e-6);
    EXPECT_NEAR(v[2], p->position.y(), 1e-6);
    EXPECT_NEAR(v[3], p->position.z(), 1e-6);
    EXPECT_EQ(static_cast<int>(v[4]), p->observation_count());
    // The keyframe of the row: the nearest timestamp (written with 6 decimals).
    auto it = kf_by_time.lower_bound(v[5] - 1e-5);
    ASSERT_NE(it, kf_by_time.end());
    ASSERT_NEAR(it->first, v[5], 1e-5);
    const auto& kf = it->second;
    ASSERT_TRUE(p->observed_by(kf.get()));
    const auto i = static_cast<std::size_t>(p->observations.at(kf.get()));
    EXPECT_NEAR(v[7], kf->f->keys_un[i].pt.x, 1e-3);
    EXPECT_NEAR(v[8], kf->f->keys_un[i].pt.y, 1e-3);
    EXPECT_EQ(static_cast<int>(v[9]), kf->f->keys_un[i].octave);
    EXPECT_NEAR(v[10], kf->f->depth[i] > 0 ? kf->f->depth[i] : 0.0, 1e-4);
    EXPECT_EQ(v[6] == 1, kf.get() == p->reference);
    ++rows[id];
    references[id] += v[6] == 1;
  }
  EXPECT_EQ(n, info.rows);
  EXPECT_EQ(static_cast<long>(rows.size()), info.points);
  EXPECT_EQ(rows.size(), by_id.size());
  EXPECT_FALSE(rows.count(retired->id));
  for (const auto& [id, p] : by_id) {
    EXPECT_EQ(rows[id], p->observation_count()) << id;
    EXPECT_EQ(references[id], 1) << id;
  }
}

TEST(MapPointsCsv, UnwritablePathNamesTheFile) {
  Map map;
  try {
    write_map_points_csv(map, "/nonexistent/dir/points.csv");
    ADD_FAILURE() << "no error";
  } catch (const Failure& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/points.csv"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace builtscene::slam
