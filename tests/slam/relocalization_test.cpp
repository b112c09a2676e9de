// Relocalization end to end (label: slow). Kidnapping: a generated sequence replayed with a
// jump back to a place mapped earlier; the SLAM must notice, relocalize within a few frames,
// and the recovered poses must match the generated ground truth in the frame aligned once on
// the frames before the jump. Real data: 7-Scenes kitchen with 30 frames cut from the middle.
#include <algorithm>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "../common/run_cli.hpp"
#include "core/so3.hpp"
#include "io/trajectory.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene::slam {
namespace {

namespace fs = std::filesystem;
using builtscene::testing::run_cli;
using builtscene::testing::shell_quote;

const fs::path kKitchen = fs::path(BUILTSCENE_SOURCE_DIR) / "../shared/data/7scenes-kitchen";

// `bs_reloc_<name>_<pid>`, removed when the test process exits.
fs::path temp(const std::string& name) { return testing::scratch_dir("reloc_" + name); }

std::vector<std::string> lines(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l);)
    if (!l.empty() && l[0] != '#') out.push_back(l);
  return out;
}

// Writes a TUM dataset at `out` replaying the frames `order` of `src` (indices into its
// rgb.txt) with fresh increasing timestamps; images are reached through symlinks.
void replay(const fs::path& src, const fs::path& out, const std::vector<int>& order) {
  fs::remove_all(out);
  fs::create_directories(out);
  fs::create_directory_symlink(fs::absolute(src / "rgb"), out / "rgb");
  fs::create_directory_symlink(fs::absolute(src / "depth"), out / "depth");
  fs::copy_file(src / "camera.yaml", out / "camera.yaml");
  const auto rgb = lines(src / "rgb.txt"), depth = lines(src / "depth.txt"), gt = lines(src / "groundtruth.txt");
  // Ground truth by timestamp (kitchen: one line per frame, same timestamps as rgb).
  std::map<std::string, std::string> gt_of;
  for (const auto& l : gt) gt_of[l.substr(0, l.find(' '))] = l.substr(l.find(' '));
  std::map<std::string, std::string> depth_of;  // depth line nearest in order: same index
  std::ofstream orgb(out / "rgb.txt"), odepth(out / "depth.txt"), ogt(out / "groundtruth.txt");
  for (std::size_t j = 0; j < order.size(); ++j) {
    const auto i = static_cast<std::size_t>(order[j]);
    char t[32];
    std::snprintf(t, sizeof(t), "%.6f", 1.0 + static_cast<double>(j) / 30.0);
    const auto& r = rgb[i];
    const auto& d = depth[i];
    orgb << t << r.substr(r.find(' ')) << "\n";
    odepth << t << d.substr(d.find(' ')) << "\n";
    const auto it = gt_of.find(r.substr(0, r.find(' ')));
    if (it != gt_of.end()) ogt << t << it->second << "\n";
  }
}

// Rigid transform taking estimated camera centres to true ones (Horn / Umeyama, no scale),
// fitted on the poses with timestamp < t_end.
Eigen::Isometry3d fit(const Trajectory& truth, const Trajectory& est, double t_end) {
  std::map<double, Eigen::Vector3d> gt;
  for (const auto& p : truth) gt[p.timestamp] = p.pose.translation();
  std::vector<Eigen::Vector3d> a, b;
  for (const auto& p : est) {
    if (p.timestamp >= t_end) continue;
    const auto it = gt.lower_bound(p.timestamp - 1e-4);
    if (it == gt.end() || std::abs(it->first - p.timestamp) > 1e-4) continue;
    a.push_back(p.pose.translation());
    b.push_back(it->second);
  }
  Eigen::Matrix3Xd A(3, a.size()), B(3, b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    A.col(static_cast<Eigen::Index>(i)) = a[i];
    B.col(static_cast<Eigen::Index>(i)) = b[i];
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.matrix() = Eigen::umeyama(A, B, false);
  return T;
}

struct RunResult {
  nlohmann::json summary;
  Trajectory estimate, truth;
};

RunResult run_slam(const fs::path& dataset, const std::string& extra = "") {
  const auto traj = dataset / "estimate.txt";
  const auto r = run_cli("slam --json --sync-mapping --dataset " + shell_quote(dataset) + " --trajectory " + shell_quote(traj) + " " + extra);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  RunResult out;
  if (r.exit_code != 0) return out;
  out.summary = nlohmann::json::parse(r.out);
  out.estimate = read_tum_trajectory(traj);
  out.truth = read_tum_trajectory(dataset / "groundtruth.txt");
  return out;
}

// Position errors of the frames with timestamp >= t_from, in the frame fitted before t_from.
std::vector<double> errors_after(const RunResult& r, double t_from) {
  const auto T = fit(r.truth, r.estimate, t_from);
  std::map<double, Eigen::Vector3d> gt;
  for (const auto& p : r.truth) gt[p.timestamp] = p.pose.translation();
  std::vector<double> e;
  for (const auto& p : r.estimate) {
    if (p.timestamp < t_from) continue;
    const auto it = gt.lower_bound(p.timestamp - 1e-4);
    if (it == gt.end() || std::abs(it->first - p.timestamp) > 1e-4) continue;
    e.push_back((T * p.pose.translation() - it->second).norm());
  }
  return e;
}

// Every kidnapping runs with ORB and with SAFT learning online (continuous, inline with
// --sync-mapping so the run is reproducible): place recognition must keep working on the
// descriptors of a net that changes between the mapping and the jump.
class Kidnapping : public ::testing::TestWithParam<std::string> {};

INSTANTIATE_TEST_SUITE_P(Descriptor, Kidnapping, ::testing::Values("orb", "saft-continuous"),
                         [](const ::testing::TestParamInfo<std::string>& i) { return i.param == "orb" ? std::string("Orb") : std::string("SaftLearning"); });

std::string descriptor_args(const std::string& p) {
  return p == "orb" ? "--descriptor orb" : "--descriptor saft --saft-mode continuous";
}

TEST_P(Kidnapping, ACameraJumpingInAGeneratedWorldRecoversTheTruePose) {
  const auto world = temp("lab");
  fs::remove_all(world);
  const auto g = run_cli("synth rgbd --scene lab-room --motion handheld --frames 200 --seed 7 --out " + shell_quote(world));
  ASSERT_EQ(g.exit_code, 0) << g.err;
  // Frames 0..149, then a jump back to frame 40 and on to 99.
  std::vector<int> order;
  for (int i = 0; i < 150; ++i) order.push_back(i);
  const int jump_at = static_cast<int>(order.size());
  for (int i = 40; i < 100; ++i) order.push_back(i);
  const auto kidnapped = temp("kidnapped");
  replay(world, kidnapped, order);
  // The jump is a real one: the camera moves far between the two frames.
  const auto gt = read_tum_trajectory(world / "groundtruth.txt");
  const double jump_m = (gt[149].pose.translation() - gt[40].pose.translation()).norm();
  const double jump_deg = so3_log(gt[149].pose.rotation() * gt[40].pose.rotation().inverse()).norm() * 180 / M_PI;
  ASSERT_TRUE(jump_m > 0.5 || jump_deg > 30) << jump_m << " m, " << jump_deg << " deg";

  const auto r = run_slam(kidnapped, descriptor_args(GetParam()));
  ASSERT_FALSE(r.summary.is_null());
  const auto& reloc = r.summary["relocalizations"];
  ASSERT_GE(reloc["count"].get<int>(), 1) << r.summary.dump();
  const long first = reloc["frames"][0].get<long>();
  // Every success was an attempt, and so was each frame between the jump (lost there; the
  // search starts on the next frame) and the first success.
  EXPECT_GE(reloc["attempts"].get<long>(), reloc["count"].get<long>() + std::max(0L, first - jump_at - 1))
      << reloc.dump();
  EXPECT_GE(first, jump_at);
  EXPECT_LE(first, jump_at + 5) << "relocalized only at frame " << first;
  // After the jump almost every frame is tracked again, at the true pose.
  const double t_jump = 1.0 + jump_at / 30.0 - 1e-6;
  const auto e = errors_after(r, t_jump);
  EXPECT_GE(e.size(), static_cast<std::size_t>(order.size() - jump_at - 6));
  double sum2 = 0, worst = 0;
  for (double x : e) {
    sum2 += x * x;
    worst = std::max(worst, x);
  }
  const double rmse = e.empty() ? 1e9 : std::sqrt(sum2 / static_cast<double>(e.size()));
  std::printf("kidnapping (%s): jump %.2f m %.0f deg; relocalized at frame %ld (jump at %d); %zu frames after, RMSE %.3f m, max %.3f m\n",
              GetParam().c_str(), jump_m, jump_deg, first, jump_at, e.size(), rmse, worst);
  EXPECT_LT(rmse, 0.05);
  EXPECT_LT(worst, 0.15);
  fs::remove_all(world);
  fs::remove_all(kidnapped);
}

double rmse(const std::vector<double>& e) {
  double sum2 = 0;
  for (double x : e) sum2 += x * x;
  return e.empty() ? 1e9 : std::sqrt(sum2 / static_cast<double>(e.size()));
}

// The kitchen camera moves slowly: cutting 30 frames (1 s) leaves at most ~21 deg / 0.15 m
// between the frames either side of the cut, which tracking may bridge without losing the
// camera. The frames after the cut must be placed correctly either way, by tracking or by
// relocalization.
TEST(Relocalization, KitchenWithThirtyFramesCutKeepsTheTruePose) {
  if (!fs::exists(kKitchen / "rgb.txt")) GTEST_SKIP() << "7scenes-kitchen not found at " << kKitchen;
  // The first 400 frames with frames 185..214 removed.
  std::vector<int> order;
  for (int i = 0; i < 400; ++i)
    if (i < 185 || i >= 215) order.push_back(i);
  const auto cut = temp("kitchen_cut");
  replay(kKitchen, cut, order);
  const auto r = run_slam(cut);
  ASSERT_FALSE(r.summary.is_null());
  const int gap = 185;
  const auto e = errors_after(r, 1.0 + gap / 30.0 - 1e-6);
  const auto& reloc = r.summary["relocalizations"];
  std::printf("kitchen cut: %d relocalizations (first at %s), lost events %d, %zu of %zu frames after the cut tracked, RMSE %.3f m\n",
              reloc["count"].get<int>(), reloc["count"].get<int>() ? reloc["frames"][0].dump().c_str() : "-",
              r.summary["lost_events"].get<int>(), e.size(), order.size() - gap, rmse(e));
  if (reloc["count"].get<int>() > 0) {
    EXPECT_LE(reloc["frames"][0].get<long>(), gap + 10);
  }
  EXPECT_GE(e.size(), order.size() - static_cast<std::size_t>(gap) - 10);
  EXPECT_LT(rmse(e), 0.10);
  fs::remove_all(cut);
}

// Real kidnapping: the first 300 kitchen frames, then a jump back to frame 80 (0.76 m,
// 30 deg away) and on to 179. Tracking cannot bridge this; relocalization must.
TEST_P(Kidnapping, KitchenCameraJumpingBackToAMappedPlaceRelocalizes) {
  if (!fs::exists(kKitchen / "rgb.txt")) GTEST_SKIP() << "7scenes-kitchen not found at " << kKitchen;
  std::vector<int> order;
  for (int i = 0; i < 300; ++i) order.push_back(i);
  const int jump_at = static_cast<int>(order.size());
  for (int i = 80; i < 180; ++i) order.push_back(i);
  const auto dir = temp("kitchen_kidnap");
  replay(kKitchen, dir, order);
  const auto r = run_slam(dir, descriptor_args(GetParam()));
  ASSERT_FALSE(r.summary.is_null());
  const auto& reloc = r.summary["relocalizations"];
  const auto e = errors_after(r, 1.0 + jump_at / 30.0 - 1e-6);
  std::printf("kitchen kidnapping (%s): %d relocalizations (first at %s, jump at %d), %zu of %zu frames after the jump tracked, RMSE %.3f m\n",
              GetParam().c_str(), reloc["count"].get<int>(), reloc["count"].get<int>() ? reloc["frames"][0].dump().c_str() : "-", jump_at,
              e.size(), order.size() - jump_at, rmse(e));
  ASSERT_GE(reloc["count"].get<int>(), 1) << r.summary.dump();
  EXPECT_GE(reloc["frames"][0].get<long>(), jump_at);
  EXPECT_LE(reloc["frames"][0].get<long>(), jump_at + 10);
  EXPECT_GE(e.size(), order.size() - static_cast<std::size_t>(jump_at) - 10);
  EXPECT_LT(rmse(e), 0.10);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace builtscene::slam
