// On a generated world: a rebuild with corrected poses gives a better map than the incremental
// map built with drifting ones (label: slow, it renders a sequence).
#include <gtest/gtest.h>

#include <cmath>

#include "../common/run_cli.hpp"
#include "io/trajectory.hpp"
#include "io/tum_dataset.hpp"
#include "ogm/map_comparison.hpp"
#include "ogm/map_server_io.hpp"
#include "ogm/poses_and_laser_scans.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene {
namespace {

namespace fs = std::filesystem;

// Drifting poses integrated one by one, then the full batch with the true poses: the rebuilt
// map must score better against the world's truth map than the drifted one (the source's
// reason for rebuilding after optimization and loop closure).
TEST(PosesAndLaserScansGenerated, RebuildWithCorrectedPosesScoresBetter) {
  const fs::path dir = testing::scratch_dir("pals_lab");
  fs::remove_all(dir);
  const auto r = testing::run_cli("synth rgbd --scene lab-room --motion robot --frames 300 --seed 5 --out " +
                                  testing::shell_quote(dir));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const TumDataset data = TumDataset::open(dir);
  const Trajectory truth = read_tum_trajectory(dir / "groundtruth.txt");
  const OccupancyGrid truth_map = load_map_server(dir / "truth_map.yaml");
  ASSERT_EQ(truth.size(), data.size());

  PosesAndLaserScansOptions o;
  o.full_batch_every = 0;  // only the explicit rebuild below
  PosesAndLaserScansEmitter e(data.settings().camera, GroundFrame::z_up(), o);
  OccupancyGridMapper drifted;
  Trajectory keyframes;
  for (std::size_t i = 0; i < data.size(); i += 10) {
    // Drift growing along the run: 1 degree of heading and 3 cm per keyframe.
    const double k = static_cast<double>(keyframes.size());
    const SE3 drift(Eigen::Quaterniond(Eigen::AngleAxisd(k * M_PI / 180.0, Eigen::Vector3d::UnitZ())),
                    Eigen::Vector3d(0.03 * k, 0, 0));
    const SE3 T_wc = drift * truth[i].pose;
    keyframes.push_back({truth[i].timestamp, T_wc});
    for (const auto& b : e.add_keyframe(truth[i].timestamp, T_wc, data.load_depth(i), keyframes))
      drifted.integrate_batch(b.pairs);
  }
  Trajectory corrected;
  for (std::size_t i = 0; i < data.size(); i += 10) corrected.push_back({truth[i].timestamp, truth[i].pose});
  OccupancyGridMapper rebuilt;
  rebuilt.integrate_batch(e.full_batch(corrected).pairs);

  const MapScore before = compare_maps(drifted.grid(), truth_map);
  const MapScore after = compare_maps(rebuilt.grid(), truth_map);
  EXPECT_GE(after.occupied_precision, 0.90);
  EXPECT_GE(after.occupied_recall, 0.85);
  EXPECT_GT(after.occupied_precision, before.occupied_precision + 0.05);
  EXPECT_EQ(rebuilt.scans_integrated(), corrected.size());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace builtscene
