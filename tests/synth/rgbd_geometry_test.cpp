// Depth of generated RGB-D sequences against the scene's own geometry (read from scene.json).
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iterator>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/errors.hpp"
#include "io/tum_dataset.hpp"
#include "rgbd_test_util.hpp"
#include "synth/renderer.hpp"
#include "synth/rgbd_sequence_writer.hpp"
#include "synth/scene_library.hpp"
#include "synth/sensor_noise.hpp"

namespace bs = builtscene;
namespace synth = builtscene::synth;
using namespace synth_test;

namespace {

std::filesystem::path generate(const std::string& scene, const std::string& tag, bool noise, int frames,
                               synth::MotionKind motion = synth::MotionKind::Handheld, int w = 320, int h = 240) {
  synth::RgbdSequenceOptions o;
  o.scene = scene;
  o.out = temp_dir(tag);
  o.frames = frames;
  o.seed = 7;
  o.kinect_noise = noise;
  o.motion = motion;
  o.width = w;
  o.height = h;
  synth::generate_rgbd_sequence(o);
  return o.out;
}

}  // namespace

TEST(RgbdGeometry, NoiseFreeDepthLiesOnSceneSurfaces) {
  for (const std::string scene : {"lab-room", "office"}) {
    const auto dir = generate(scene, "exact_" + scene, false, 4);
    const JsonScene js = load_scene_json(dir / "scene.json");
    const auto ds = bs::TumDataset::open(dir);
    const auto gt = ds.groundtruth();
    ASSERT_EQ(gt.size(), ds.size());
    std::size_t n = 0, bad = 0;
    double worst = 0;
    for (std::size_t i = 0; i < ds.size(); ++i) {
      const cv::Mat d = ds.load_depth(i);
      for (int y = 0; y < d.rows; y += 3)
        for (int x = 0; x < d.cols; x += 3) {
          const float z = d.at<float>(y, x);
          if (z <= 0) continue;
          const Eigen::Vector3d pw = gt[i].pose * ds.settings().camera.unproject({x, y}, z);
          const double e = distance_to_surfaces(js, pw);
          worst = std::max(worst, e);
          ++n;
          if (e > 1e-3) ++bad;
        }
    }
    EXPECT_GT(n, 4u * 2000u) << scene;
    // Exact up to the PNG's 0.2 mm steps; allow a handful of pixels where float precision at
    // a silhouette picks the neighbouring surface.
    EXPECT_LE(static_cast<double>(bad), 0.001 * n) << scene << ": worst " << worst;
    std::filesystem::remove_all(dir);
  }
}

TEST(RgbdGeometry, KinectDepthWithinNoiseModel) {
  const auto dir = generate("lab-room", "kinect", true, 4);
  const JsonScene js = load_scene_json(dir / "scene.json");
  const auto ds = bs::TumDataset::open(dir);
  const auto gt = ds.groundtruth();
  const double fx = ds.settings().camera.fx;
  std::size_t n = 0, within = 0, total = 0;
  for (std::size_t i = 0; i < ds.size(); ++i) {
    const cv::Mat d = ds.load_depth(i);
    total += d.total();
    for (int y = 0; y < d.rows; y += 2)
      for (int x = 0; x < d.cols; x += 2) {
        const float z = d.at<float>(y, x);
        if (z <= 0) continue;
        EXPECT_GE(z, 0.5f);
        EXPECT_LE(z, 8.0f);
        const Eigen::Vector3d pw = gt[i].pose * ds.settings().camera.unproject({x, y}, z);
        const double e = distance_to_surfaces(js, pw);
        // 3 sigma axial + one disparity step (1/8 px at 0.075 m x 580 px) + a lateral shift of
        // up to 2 px on a slanted surface.
        const double tol = 3 * synth::KinectNoiseModel::axial_sigma(z) + z * z / (0.075 * 580) / 8 + 2 * z / fx;
        ++n;
        if (e <= tol) ++within;
      }
  }
  ASSERT_GT(n, 1000u);
  EXPECT_GE(static_cast<double>(within) / n, 0.97);
  std::filesystem::remove_all(dir);
}

TEST(RgbdGeometry, WorldPointsReprojectConsistentlyBetweenFrames) {
  const auto dir = generate("lab-room", "reproj", false, 12);
  const auto ds = bs::TumDataset::open(dir);
  const auto gt = ds.groundtruth();
  const auto& cam = ds.settings().camera;
  for (std::size_t a : {0u, 4u}) {
    const std::size_t b = a + 7;
    const cv::Mat da = ds.load_depth(a), db = ds.load_depth(b);
    std::size_t inside = 0, consistent = 0, occluded = 0, behind = 0;
    for (int y = 0; y < da.rows; y += 4)
      for (int x = 0; x < da.cols; x += 4) {
        const float z = da.at<float>(y, x);
        if (z <= 0) continue;
        const Eigen::Vector3d pw = gt[a].pose * cam.unproject({x, y}, z);
        const Eigen::Vector3d pb = gt[b].pose.inverse() * pw;
        if (pb.z() <= 0.1) continue;
        const Eigen::Vector2d uv = cam.project(pb);
        const int u = static_cast<int>(std::lround(uv.x())), v = static_cast<int>(std::lround(uv.y()));
        if (u < 1 || v < 1 || u >= db.cols - 1 || v >= db.rows - 1) continue;
        ++inside;
        // Depth is sampled at the nearest pixel centre: allow the surface slope over half a
        // pixel diagonal.
        const double tol = 0.002 + pb.z() * 3.0 / cam.fx;
        const float zb = db.at<float>(v, u);
        if (std::abs(zb - pb.z()) <= tol) ++consistent;
        else if (zb > 0 && zb < pb.z()) ++occluded;
        else ++behind;
      }
    ASSERT_GT(inside, 200u);
    EXPECT_GE(static_cast<double>(consistent) / inside, 0.85) << "occluded " << occluded << " behind " << behind;
    // A surface point can be hidden in the other view, but never seen through.
    EXPECT_LE(static_cast<double>(behind) / inside, 0.03);
  }
  std::filesystem::remove_all(dir);
}

TEST(RgbdGeometry, RasterizedDepthMatchesRayCasting) {
  const synth::Scene scene = synth::build_scene("corridor-loop");
  const auto settings = synth::kinect_settings(160, 120);
  const synth::Renderer renderer(scene, settings.camera);
  const auto surfaces = synth::scene_surfaces(scene);
  const auto& cam = settings.camera;
  for (const bs::SE3& pose : {bs::SE3(synth::look_rotation({1, 0.2, -0.1}, 0.05), {3, 1.1, 1.2}),
                              bs::SE3(synth::look_rotation({-0.3, 1, -0.4}, -0.1), {26, 4, 1.0})}) {
    synth::RenderOutput out;
    renderer.render(pose, out, 2);
    std::size_t n = 0, bad = 0;
    for (int y = 0; y < 120; ++y)
      for (int x = 0; x < 160; ++x) {
        const Eigen::Vector3d ray((x - cam.cx) / cam.fx, (y - cam.cy) / cam.fy, 1.0);
        const Eigen::Vector3d dw = pose.rotation_matrix() * ray;
        const auto t = synth::raycast(surfaces, pose.translation(), dw, 0.02);
        const float z = out.depth.at<float>(y, x);
        ++n;
        if (!t) {
          if (z != 0.f) ++bad;
          continue;
        }
        if (std::abs(*t - z) > 1e-4 * std::max(1.0, *t)) ++bad;
      }
    EXPECT_LE(bad, n / 500) << "pixels where the rasterizer and the ray caster disagree";
  }
}

TEST(RgbdGeometry, SameSeedSameBytes) {
  synth::RgbdSequenceOptions o;
  o.scene = "demo";
  o.frames = 3;
  o.seed = 11;
  o.blur = true;
  o.exposure_changes = true;
  o.width = 160;
  o.height = 120;
  o.out = temp_dir("det_a");
  synth::generate_rgbd_sequence(o);
  const auto a = o.out;
  o.out = temp_dir("det_b");
  o.render_threads = 2;  // the thread count must not change a byte
  synth::generate_rgbd_sequence(o);
  const auto b = o.out;
  auto read = [](const std::filesystem::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
  };
  std::size_t files = 0;
  for (const auto& e : std::filesystem::recursive_directory_iterator(a)) {
    if (!e.is_regular_file()) continue;
    const auto rel = std::filesystem::relative(e.path(), a);
    ASSERT_TRUE(std::filesystem::exists(b / rel)) << rel;
    EXPECT_EQ(read(e.path()), read(b / rel)) << rel;
    ++files;
  }
  EXPECT_EQ(files, 8u + 6u);  // 8 ground-truth and list files, 3 RGB + 3 depth images
  o.seed = 12;
  o.out = temp_dir("det_c");
  synth::generate_rgbd_sequence(o);
  EXPECT_NE(read(a / "groundtruth.txt"), read(o.out / "groundtruth.txt"));
  for (const auto& d : {a, b, o.out}) std::filesystem::remove_all(d);
}

// The first and the last colour frame of a generated folder, in grey.
std::pair<cv::Mat, cv::Mat> first_and_last_frames(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir / "rgb")) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return {cv::imread(files.front().string(), cv::IMREAD_GRAYSCALE), cv::imread(files.back().string(), cv::IMREAD_GRAYSCALE)};
}

TEST(RgbdGeometry, ALongerShutterSmearsMore) {
  // The same frames of a moving camera, without blur and with 10 ms and 33 ms shutters: the
  // image's fine detail (variance of the Laplacian, noise off) must fall as the shutter opens.
  auto sharpness = [](const std::filesystem::path& dir) {
    const cv::Mat img = first_and_last_frames(dir).second;  // the camera is moving by then
    cv::Mat lap;
    cv::Laplacian(img, lap, CV_64F);
    cv::Scalar mean, sd;
    cv::meanStdDev(lap, mean, sd);
    return sd[0] * sd[0];
  };
  synth::RgbdSequenceOptions o;
  o.scene = "lab-room";
  o.frames = 12;
  o.seed = 3;
  o.kinect_noise = false;
  o.out = temp_dir("shutter_none");
  synth::generate_rgbd_sequence(o);
  const double none = sharpness(o.out);
  std::filesystem::remove_all(o.out);
  o.blur = true;
  std::vector<double> blurred;
  for (const double s : {0.010, 0.033}) {
    o.exposure_time_s = s;
    o.out = temp_dir("shutter");
    const auto j = synth::generate_rgbd_sequence(o);
    EXPECT_GT(j.at("blur_subframes_max").get<int>(), 1);
    blurred.push_back(sharpness(o.out));
    std::filesystem::remove_all(o.out);
  }
  EXPECT_LT(blurred[0], 0.95 * none);
  EXPECT_LT(blurred[1], 0.95 * blurred[0]);
}

TEST(RgbdGeometry, FadingLightKeepsTheBrightnessAndRaisesTheNoise) {
  // Same motion and noise seed, with and without a fade to 5 % of the light: the first frame
  // (full light) is the same image; in the last one auto-gain keeps the mean brightness while
  // the sensor noise, amplified 20 times, grows far above the unfaded camera's.
  synth::RgbdSequenceOptions o;
  o.scene = "lab-room";
  o.frames = 5;
  o.seed = 4;
  o.width = 320;
  o.height = 240;
  auto frames = [&](double fade) {
    o.light_fade_to = fade;
    o.out = temp_dir("fade");
    synth::generate_rgbd_sequence(o);
    auto out = first_and_last_frames(o.out);
    std::filesystem::remove_all(o.out);
    return out;
  };
  const auto steady = frames(1.0), faded = frames(0.05);
  EXPECT_EQ(cv::norm(steady.first, faded.first, cv::NORM_INF), 0.0);
  cv::Mat diff;
  cv::subtract(faded.second, steady.second, diff, cv::noArray(), CV_32F);
  cv::Scalar mean, sd;
  cv::meanStdDev(diff, mean, sd);
  EXPECT_LT(std::abs(mean[0]), 6.0);  // clipping at 255 of the brighter noise shifts it a little
  EXPECT_GT(sd[0], 8.0);              // the unfaded read noise is 1.6 levels
}

// `--noise depth` and `--noise image` are each one part of the Kinect model: the depth-only
// sequence has the noise-free colour and the Kinect depth, the image-only one the reverse
// (byte for byte; the two parts draw from separate random streams).
TEST(RgbdGeometry, DepthAndImageNoiseAreTheTwoPartsOfTheKinectModel) {
  auto make = [](const std::string& tag, bool kinect, bool depth, bool image) {
    synth::RgbdSequenceOptions o;
    o.scene = "lab-room";
    o.out = temp_dir("noise_part_" + tag);
    o.frames = 2;
    o.seed = 3;
    o.kinect_noise = kinect;
    o.depth_noise = depth;
    o.image_noise = image;
    o.width = 160;
    o.height = 120;
    synth::generate_rgbd_sequence(o);
    return o.out;
  };
  const auto none = make("none", false, true, true), kinect = make("kinect", true, true, true),
             depth = make("depth", true, true, false), image = make("image", true, false, true);
  auto same = [](const std::filesystem::path& a, const std::filesystem::path& b, const char* file) {
    const cv::Mat x = cv::imread((a / file).string(), cv::IMREAD_UNCHANGED), y = cv::imread((b / file).string(), cv::IMREAD_UNCHANGED);
    EXPECT_FALSE(x.empty()) << a / file;
    return !x.empty() && x.size == y.size && x.type() == y.type() && cv::norm(x, y, cv::NORM_INF) == 0;
  };
  for (const char* frame : {"000000.png", "000001.png"}) {
    const std::string rgb = std::string("rgb/") + frame, d = std::string("depth/") + frame;
    EXPECT_FALSE(same(none, kinect, rgb.c_str())) << "the Kinect model changes the colour";
    EXPECT_FALSE(same(none, kinect, d.c_str())) << "the Kinect model changes the depth";
    EXPECT_TRUE(same(depth, none, rgb.c_str()));
    EXPECT_TRUE(same(depth, kinect, d.c_str()));
    EXPECT_TRUE(same(image, kinect, rgb.c_str()));
    EXPECT_TRUE(same(image, none, d.c_str()));
  }
}

// `--first-frame` writes a slice of the sequence: each frame it writes has the name, time,
// pose and bytes of the same frame in the whole sequence, and nothing before it is written.
TEST(RgbdGeometry, AFirstFrameSliceEqualsThatPartOfTheWholeSequence) {
  auto make = [](const std::string& tag, int first) {
    synth::RgbdSequenceOptions o;
    o.scene = "corridor-loop";
    o.motion = synth::MotionKind::Robot;
    o.out = temp_dir("slice_" + tag);
    o.frames = 4;
    o.first_frame = first;
    o.seed = 2;
    o.width = 160;
    o.height = 120;
    const auto j = synth::generate_rgbd_sequence(o);
    EXPECT_EQ(j.at("frames").get<int>(), 4 - first);
    return o.out;
  };
  const auto whole = make("whole", 0), slice = make("from2", 2);
  EXPECT_FALSE(std::filesystem::exists(slice / "rgb" / "000001.png"));
  for (const char* file : {"rgb/000002.png", "depth/000002.png", "rgb/000003.png", "depth/000003.png"}) {
    const cv::Mat x = cv::imread((whole / file).string(), cv::IMREAD_UNCHANGED), y = cv::imread((slice / file).string(), cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(y.empty()) << slice / file;
    ASSERT_EQ(x.size, y.size);
    EXPECT_EQ(cv::norm(x, y, cv::NORM_INF), 0.0) << file;
  }
  auto lines = [](const std::filesystem::path& p) {
    std::vector<std::string> out;
    std::ifstream in(p);
    for (std::string l; std::getline(in, l);)
      if (!l.empty() && l[0] != '#') out.push_back(l);
    return out;
  };
  const auto gt_whole = lines(whole / "groundtruth.txt"), gt_slice = lines(slice / "groundtruth.txt");
  ASSERT_EQ(gt_whole.size(), 4u);
  ASSERT_EQ(gt_slice.size(), 2u);
  EXPECT_EQ(gt_slice[0], gt_whole[2]);
  EXPECT_EQ(gt_slice[1], gt_whole[3]);
  const auto rgb_whole = lines(whole / "rgb.txt");
  ASSERT_EQ(rgb_whole.size(), 4u);
  EXPECT_EQ(lines(slice / "rgb.txt"), std::vector<std::string>(rgb_whole.begin() + 2, rgb_whole.end()));
  synth::RgbdSequenceOptions bad;
  bad.scene = "lab-room";
  bad.frames = 3;
  bad.first_frame = 3;
  bad.out = temp_dir("slice_bad");
  EXPECT_THROW(synth::generate_rgbd_sequence(bad), builtscene::InputError);
  for (const auto& d : {whole, slice, bad.out}) std::filesystem::remove_all(d);
}
