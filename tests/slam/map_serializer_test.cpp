// Saved maps: the decoded map equals the one encoded (checked field by field against the
// built map, not against the decoder's own output), save -> load -> save is byte-identical,
// and every kind of damaged file is rejected with an InputError naming the file, never a crash.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "core/errors.hpp"
#include "map_test_fixture.hpp"
#include "slam/map_serializer.hpp"
#include "slam/plane_landmark.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene::slam {
namespace {

struct Built {
  std::shared_ptr<const FrameContext> ctx = test::kinect_context();
  Map map;
  std::vector<std::uint8_t> bytes;
  explicit Built(int kfs = 12, int keys = 150) {
    std::lock_guard lock(map.mutex());
    test::build_random_map(map, ctx, kfs, keys);
    bytes = encode_map(map, *ctx, 0);
  }
};

std::string decode_error(const std::vector<std::uint8_t>& bytes, const std::shared_ptr<const FrameContext>& ctx,
                         Map& target, std::optional<std::uint64_t> vocabulary = std::nullopt) {
  try {
    std::lock_guard lock(target.mutex());
    decode_map(bytes.data(), bytes.size(), "test.map", target, ctx, vocabulary);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

void set_u32(std::vector<std::uint8_t>& b, std::size_t at, std::uint32_t v) { std::memcpy(b.data() + at, &v, 4); }
void fix_header_crc(std::vector<std::uint8_t>& b) { set_u32(b, 40, map_file_crc32(b.data(), 40)); }

// A file taken apart into its sections (tag, payload) and put together again with a given
// version, recomputing every size and checksum: how older versions and damaged sections are
// made from a fresh file.
struct Section {
  std::string tag;
  std::vector<std::uint8_t> payload;
};
std::vector<Section> split_sections(const std::vector<std::uint8_t>& b) {
  std::vector<Section> out;
  for (std::size_t pos = 48; pos + 16 <= b.size();) {
    std::uint64_t n;
    std::memcpy(&n, b.data() + pos + 8, 8);
    out.push_back({std::string(reinterpret_cast<const char*>(b.data() + pos), 4),
                   std::vector<std::uint8_t>(b.begin() + static_cast<long>(pos + 16), b.begin() + static_cast<long>(pos + 16 + n))});
    pos += 16 + n;
  }
  return out;
}
std::vector<std::uint8_t> join_sections(const std::vector<std::uint8_t>& original, std::uint32_t version,
                                        const std::vector<Section>& sections) {
  std::vector<std::uint8_t> b(original.begin(), original.begin() + 48);
  for (const auto& s : sections) {
    const std::size_t at = b.size();
    b.resize(at + 16);
    std::memcpy(b.data() + at, s.tag.data(), 4);
    set_u32(b, at + 4, map_file_crc32(s.payload.data(), s.payload.size()));
    const std::uint64_t n = s.payload.size();
    std::memcpy(b.data() + at + 8, &n, 8);
    b.insert(b.end(), s.payload.begin(), s.payload.end());
  }
  set_u32(b, 8, version);
  set_u32(b, 24, static_cast<std::uint32_t>(sections.size()));
  const std::uint64_t body = b.size() - 48;
  std::memcpy(b.data() + 32, &body, 8);
  fix_header_crc(b);
  return b;
}
template <typename T>
void append(std::vector<std::uint8_t>& b, T v) {
  const std::size_t at = b.size();
  b.resize(at + sizeof(T));
  std::memcpy(b.data() + at, &v, sizeof(T));
}

TEST(MapSerializer, DecodedMapEqualsTheBuiltOne) {
  Built a;
  Map loaded;
  std::lock_guard la(a.map.mutex());
  std::lock_guard lb(loaded.mutex());
  const auto info = decode_map(a.bytes.data(), a.bytes.size(), "mem", loaded, a.ctx);
  EXPECT_EQ(info.keyframes, 12u);
  EXPECT_EQ(info.points, a.map.point_count());
  const auto kfa = a.map.keyframes(), kfb = loaded.keyframes();
  ASSERT_EQ(kfa.size(), kfb.size());
  for (std::size_t k = 0; k < kfa.size(); ++k) {
    const auto &x = *kfa[k], &y = *kfb[k];
    EXPECT_EQ(x.id, y.id);
    EXPECT_EQ(x.frame_id, y.frame_id);
    EXPECT_EQ(x.timestamp, y.timestamp);
    EXPECT_LT((x.pose().matrix() - y.pose().matrix()).norm(), 1e-12);
    EXPECT_EQ(x.keep, y.keep);
    ASSERT_EQ(x.f->size(), y.f->size());
    EXPECT_EQ(cv::norm(x.f->descriptors, y.f->descriptors, cv::NORM_HAMMING), 0);
    for (std::size_t i = 0; i < x.f->size(); ++i) {
      EXPECT_EQ(x.f->keys_un[i].pt, y.f->keys_un[i].pt);
      EXPECT_EQ(x.f->keys_un[i].octave, y.f->keys_un[i].octave);
      EXPECT_EQ(x.f->keys_un[i].angle, y.f->keys_un[i].angle);
      EXPECT_EQ(x.f->depth[i], y.f->depth[i]);
      EXPECT_EQ(x.f->u_right[i], y.f->u_right[i]);
      EXPECT_EQ(x.points[i] ? x.points[i]->id : -1, y.points[i] ? y.points[i]->id : -1);
    }
    EXPECT_EQ(x.parent ? x.parent->id : -1, y.parent ? y.parent->id : -1);
    EXPECT_EQ(x.children.size(), y.children.size());
    ASSERT_EQ(x.ordered_connections.size(), y.ordered_connections.size());
    for (std::size_t c = 0; c < x.ordered_connections.size(); ++c) {
      EXPECT_EQ(x.ordered_connections[c]->id, y.ordered_connections[c]->id);
      EXPECT_EQ(x.connections.at(x.ordered_connections[c]), y.connections.at(y.ordered_connections[c]));
    }
    // The area grid is rebuilt: the same query finds the same keypoints.
    EXPECT_EQ(x.f->in_area(320, 240, 60), y.f->in_area(320, 240, 60));
  }
  const auto pa = a.map.points(), pb = loaded.points();
  ASSERT_EQ(pa.size(), pb.size());
  for (std::size_t k = 0; k < pa.size(); ++k) {
    const auto &x = *pa[k], &y = *pb[k];
    EXPECT_EQ(x.id, y.id);
    EXPECT_EQ(x.position, y.position);
    EXPECT_EQ(x.normal, y.normal);
    EXPECT_EQ(x.min_distance, y.min_distance);
    EXPECT_EQ(x.max_distance, y.max_distance);
    EXPECT_EQ(x.visible, y.visible);
    EXPECT_EQ(x.found, y.found);
    EXPECT_EQ(cv::norm(x.descriptor, y.descriptor, cv::NORM_HAMMING), 0);
    ASSERT_EQ(x.observations.size(), y.observations.size());
    std::map<long, int> ox, oy;
    for (const auto& [kf, i] : x.observations) ox[kf->id] = i;
    for (const auto& [kf, i] : y.observations) oy[kf->id] = i;
    EXPECT_EQ(ox, oy);
    EXPECT_EQ(x.reference ? x.reference->id : -1, y.reference ? y.reference->id : -1);
  }
  EXPECT_EQ(loaded.peek_next_keyframe_id(), a.map.peek_next_keyframe_id());
  EXPECT_EQ(loaded.peek_next_point_id(), a.map.peek_next_point_id());
}

TEST(MapSerializer, SaveLoadSaveIsByteIdentical) {
  Built a;
  Map loaded;
  std::lock_guard lb(loaded.mutex());
  decode_map(a.bytes.data(), a.bytes.size(), "mem", loaded, a.ctx);
  EXPECT_EQ(encode_map(loaded, *a.ctx, 0), a.bytes);
}

TEST(MapSerializer, FilesRoundTripAndNameThemselvesInErrors) {
  Built a;
  const auto dir = testing::scratch_dir("map_test");
  const auto path = dir / "room.map";
  write_map_file(path, a.map, *a.ctx);
  EXPECT_FALSE(std::filesystem::exists(dir / "room.map.tmp"));
  Map loaded;
  const auto info = read_map_file(path, loaded, a.ctx);
  EXPECT_EQ(info.bytes, a.bytes.size());
  EXPECT_EQ(std::filesystem::file_size(path), a.bytes.size());
  std::filesystem::resize_file(path, a.bytes.size() / 2);
  try {
    read_map_file(path, loaded, a.ctx);
    ADD_FAILURE() << "truncated file accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_map_file(dir / "missing.map", loaded, a.ctx), InputError);
  EXPECT_THROW(write_map_file(dir / "no" / "such" / "dir.map", a.map, *a.ctx), InputError);
  std::filesystem::remove_all(dir);
}

TEST(MapSerializer, TruncationAtAnyOffsetIsRejectedAndLeavesTheTargetAlone) {
  Built a(5, 60);
  Built other(3, 40);
  std::vector<std::size_t> cuts;
  for (std::size_t n = 0; n < 200 && n < a.bytes.size(); ++n) cuts.push_back(n);
  for (std::size_t n = 200; n < a.bytes.size(); n += 97) cuts.push_back(n);
  cuts.push_back(a.bytes.size() - 1);
  for (std::size_t n : cuts) {
    std::vector<std::uint8_t> cut(a.bytes.begin(), a.bytes.begin() + static_cast<long>(n));
    const std::string err = decode_error(cut, a.ctx, other.map);
    EXPECT_NE(err, "") << "accepted a file cut at " << n;
    EXPECT_EQ(err.rfind("test.map:", 0), 0u) << err;
  }
  std::lock_guard lock(other.map.mutex());
  EXPECT_EQ(other.map.keyframe_count(), 3u);  // untouched by every failed load
}

TEST(MapSerializer, EveryFlippedByteIsDetected) {
  Built a(4, 50);
  Map target;
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> bit(0, 7);
  for (std::size_t at = 0; at < a.bytes.size(); at += (at < 64 ? 1 : 13)) {
    auto b = a.bytes;
    b[at] ^= static_cast<std::uint8_t>(1u << bit(rng));
    EXPECT_NE(decode_error(b, a.ctx, target), "") << "flip at byte " << at << " went unnoticed";
  }
}

TEST(MapSerializer, WrongVersionForeignFilesAndOtherByteOrder) {
  Built a(3, 30);
  Map target;
  auto next = a.bytes;  // a version from a future build
  set_u32(next, 8, kMapFileVersion + 1);
  fix_header_crc(next);
  const std::string expected = "version " + std::to_string(kMapFileVersion + 1) + " is not supported";
  EXPECT_NE(decode_error(next, a.ctx, target).find(expected), std::string::npos) << decode_error(next, a.ctx, target);
  auto v0 = a.bytes;
  set_u32(v0, 8, 0);
  fix_header_crc(v0);
  EXPECT_NE(decode_error(v0, a.ctx, target).find("version 0 is not supported"), std::string::npos);

  auto be = a.bytes;
  set_u32(be, 12, 0x04030201u);
  fix_header_crc(be);
  EXPECT_NE(decode_error(be, a.ctx, target).find("byte order"), std::string::npos);

  std::mt19937 rng(11);
  std::uniform_int_distribution<int> byte(0, 255);
  for (std::size_t size : {0, 1, 7, 8, 47, 48, 1000, 100000}) {
    std::vector<std::uint8_t> junk(size);
    for (auto& c : junk) c = static_cast<std::uint8_t>(byte(rng));
    EXPECT_NE(decode_error(junk, a.ctx, target).find("not a builtscene map"), std::string::npos);
    // With a valid signature the header checks catch it instead.
    if (size >= 8) {
      std::memcpy(junk.data(), a.bytes.data(), 8);
      EXPECT_NE(decode_error(junk, a.ctx, target), "");
    }
  }
  const std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex 0\nend_header\n";
  EXPECT_NE(decode_error(std::vector<std::uint8_t>(ply.begin(), ply.end()), a.ctx, target), "");
}

TEST(MapSerializer, OtherCameraOrVocabularyIsRejected) {
  Built a(3, 30);
  Map target;
  auto settings = test::kinect_settings();
  settings.camera.fx = 520;
  const auto other_camera = FrameContext::make(settings, ScalePyramid::make(1.2f, 8), DescriptorMetric::orb());
  EXPECT_NE(decode_error(a.bytes, other_camera, target).find("Camera.fx"), std::string::npos);
  const auto other_pyramid =
      FrameContext::make(test::kinect_settings(), ScalePyramid::make(1.2f, 6), DescriptorMetric::orb());
  EXPECT_NE(decode_error(a.bytes, other_pyramid, target).find("nLevels"), std::string::npos);

  std::vector<std::uint8_t> with_vocab;
  {
    std::lock_guard lock(a.map.mutex());
    with_vocab = encode_map(a.map, *a.ctx, 0x1234);
  }
  EXPECT_EQ(decode_error(with_vocab, a.ctx, target, 0x1234), "");
  EXPECT_NE(decode_error(with_vocab, a.ctx, target, 0x9999).find("vocabulary"), std::string::npos);
}

// A consistent checksum does not make nonsense content acceptable: references are checked.
TEST(MapSerializer, DanglingReferencesAreRejectedEvenWithValidChecksums) {
  Built a(3, 30);
  Map target;
  // Point section: make the first observation name a keyframe that does not exist.
  std::size_t pos = 48;
  std::vector<std::pair<std::size_t, std::size_t>> sections;  // payload offset, size
  for (int s = 0; s < 4; ++s) {
    std::uint64_t n;
    std::memcpy(&n, a.bytes.data() + pos + 8, 8);
    sections.emplace_back(pos + 16, n);
    pos += 16 + n;
  }
  auto b = a.bytes;
  const std::size_t first_point = sections[2].first + 4;
  const std::size_t first_obs = first_point + 8 + 48 + 8 + 16 + 8 + 32 + 4;
  const std::int64_t bogus = 999;
  std::memcpy(b.data() + first_obs, &bogus, 8);
  set_u32(b, sections[2].first - 12, map_file_crc32(b.data() + sections[2].first, sections[2].second));
  const std::string err = decode_error(b, a.ctx, target);
  EXPECT_NE(err.find("unknown id 999"), std::string::npos) << err;
}

// Loop edges (version 2): saved once per pair, restored on both ends.
TEST(MapSerializer, LoopEdgesRoundTrip) {
  Built a(8, 60);
  {
    std::lock_guard lock(a.map.mutex());
    const auto kfs = a.map.keyframes();
    for (auto [i, j] : {std::pair{0, 5}, std::pair{2, 7}}) {
      kfs[static_cast<std::size_t>(i)]->loop_edges.insert(kfs[static_cast<std::size_t>(j)].get());
      kfs[static_cast<std::size_t>(j)]->loop_edges.insert(kfs[static_cast<std::size_t>(i)].get());
    }
    a.bytes = encode_map(a.map, *a.ctx, 0);
  }
  Map loaded;
  std::lock_guard lb(loaded.mutex());
  decode_map(a.bytes.data(), a.bytes.size(), "mem", loaded, a.ctx);
  const auto kfs = loaded.keyframes();
  ASSERT_EQ(kfs.size(), 8u);
  std::set<std::pair<long, long>> edges;
  for (const auto& kf : kfs)
    for (const KeyFrame* o : kf->loop_edges) edges.insert({kf->id, o->id});
  EXPECT_EQ(edges, (std::set<std::pair<long, long>>{{0, 5}, {5, 0}, {2, 7}, {7, 2}}));
  EXPECT_EQ(encode_map(loaded, *a.ctx, 0), a.bytes);
}

// A keyframe that joined the tree through the depth-odometry bridge keeps that mark (the
// loop closer weighs its tree edge as odometry), and the others keep theirs.
TEST(MapSerializer, OdometryTreeLinksRoundTrip) {
  Built a(8, 60);
  {
    std::lock_guard lock(a.map.mutex());
    a.map.keyframes()[3]->parent_by_odometry = true;
    a.bytes = encode_map(a.map, *a.ctx, 0);
  }
  Map loaded;
  std::lock_guard lb(loaded.mutex());
  decode_map(a.bytes.data(), a.bytes.size(), "mem", loaded, a.ctx);
  const auto kfs = loaded.keyframes(), built = a.map.keyframes();
  ASSERT_EQ(kfs.size(), 8u);
  for (std::size_t k = 0; k < kfs.size(); ++k) {
    EXPECT_EQ(kfs[k]->parent_by_odometry, kfs[k]->id == 3) << kfs[k]->id;
    EXPECT_EQ(kfs[k]->has_parent_link, built[k]->has_parent_link) << kfs[k]->id;
  }
  EXPECT_EQ(encode_map(loaded, *a.ctx, 0), a.bytes);
}

// Older files are the same map without what their version lacked: version 1 had no LOOP
// section (loop edges), version 2 no DLNK section (depth links), version 3 no PLAN section
// (plane landmarks). Saved again, they are today's version.
TEST(MapSerializer, OlderVersionsStillLoad) {
  Built a(6, 50);
  const auto sections = split_sections(a.bytes);
  ASSERT_EQ(sections.size(), 7u);
  ASSERT_EQ(sections[4].tag, "LOOP");
  ASSERT_EQ(sections[5].tag, "DLNK");
  ASSERT_EQ(sections[6].tag, "PLAN");
  for (std::uint32_t version : {1u, 2u, 3u}) {
    const auto old = join_sections(a.bytes, version, std::vector<Section>(sections.begin(), sections.begin() + 3 + version));
    Map loaded;
    ASSERT_EQ(decode_error(old, a.ctx, loaded), "") << "version " << version;
    std::lock_guard lb(loaded.mutex());
    EXPECT_EQ(loaded.keyframe_count(), 6u);
    EXPECT_EQ(encode_map(loaded, *a.ctx, 0), a.bytes) << "version " << version;
    // A newer header over an older version's sections is not accepted.
    auto mixed = old;
    set_u32(mixed, 8, version + 1);
    fix_header_crc(mixed);
    Map target;
    EXPECT_NE(decode_error(mixed, a.ctx, target), "") << "version " << version;
  }
}

TEST(MapSerializer, BadLoopEdgesAreRejected) {
  Built a(6, 50);
  auto with_loop = [&](std::int64_t x, std::int64_t y, int copies) {
    auto sections = split_sections(a.bytes);
    auto& payload = sections[4].payload;
    payload.clear();
    append(payload, static_cast<std::uint32_t>(copies));
    for (int c = 0; c < copies; ++c) {
      append(payload, x);
      append(payload, y);
    }
    return join_sections(a.bytes, kMapFileVersion, sections);
  };
  Map target;
  EXPECT_EQ(decode_error(with_loop(1, 4, 1), a.ctx, target), "");
  EXPECT_NE(decode_error(with_loop(3, 3, 1), a.ctx, target).find("loop edge to itself"), std::string::npos);
  EXPECT_NE(decode_error(with_loop(1, 4, 2), a.ctx, target).find("appears twice"), std::string::npos);
  EXPECT_NE(decode_error(with_loop(1, 99, 1), a.ctx, target), "");
}

// Depth links (version 3): the relative pose and the full information come back exactly,
// links to keyframes not in the map are not written, and saving again gives the same bytes.
TEST(MapSerializer, DepthLinksRoundTrip) {
  Built a(8, 60);
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  std::map<long, std::pair<long, Eigen::Matrix<double, 6, 6>>> expected;
  {
    std::lock_guard lock(a.map.mutex());
    const auto kfs = a.map.keyframes();
    for (auto [i, j] : {std::pair{3, 2}, std::pair{6, 1}}) {
      Eigen::Matrix<double, 6, 6> J;
      for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 6; ++c) J(r, c) = g(rng);
      const Eigen::Matrix<double, 6, 6> JtJ = 1e4 * J.transpose() * J;
      const Eigen::Matrix<double, 6, 6> info = 0.5 * (JtJ + JtJ.transpose());  // exactly symmetric, positive definite
      auto& kf = *kfs[static_cast<std::size_t>(i)];
      kf.depth_link_to = kfs[static_cast<std::size_t>(j)];
      kf.depth_link_T = SE3(Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * i, Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized())),
                            Eigen::Vector3d(g(rng), g(rng), g(rng)));
      kf.depth_link_information = info;
      expected[kf.id] = {kfs[static_cast<std::size_t>(j)]->id, info};
    }
    // Links whose target is not in the map (culled, still referenced elsewhere) or gone
    // (freed) are not saved.
    const auto culled = std::make_shared<KeyFrame>(99, Frame(99, 9.9, kfs[0]->f));
    kfs[5]->depth_link_to = culled;
    kfs[7]->depth_link_to = std::make_shared<KeyFrame>(98, Frame(98, 9.8, kfs[0]->f));
    a.bytes = encode_map(a.map, *a.ctx, 0);
  }
  Map loaded;
  std::lock_guard la(a.map.mutex());
  std::lock_guard lb(loaded.mutex());
  decode_map(a.bytes.data(), a.bytes.size(), "mem", loaded, a.ctx);
  const auto kfs = loaded.keyframes(), built = a.map.keyframes();
  ASSERT_EQ(kfs.size(), 8u);
  for (std::size_t k = 0; k < kfs.size(); ++k) {
    const auto to = kfs[k]->depth_link_to.lock();
    const auto it = expected.find(kfs[k]->id);
    if (it == expected.end()) {
      EXPECT_FALSE(to) << kfs[k]->id;
      continue;
    }
    ASSERT_TRUE(to) << kfs[k]->id;
    EXPECT_EQ(to->id, it->second.first);
    EXPECT_EQ(to.get(), kfs[static_cast<std::size_t>(it->second.first)].get());  // the loaded map's own keyframe
    EXPECT_LT((kfs[k]->depth_link_T.matrix() - built[k]->depth_link_T.matrix()).norm(), 1e-12);
    EXPECT_EQ(kfs[k]->depth_link_information, it->second.second);
  }
  EXPECT_EQ(encode_map(loaded, *a.ctx, 0), a.bytes);
}

TEST(MapSerializer, BadDepthLinksAreRejected) {
  Built a(6, 50);
  auto with_link = [&](std::int64_t from, std::int64_t to, int copies, double info_diag) {
    auto sections = split_sections(a.bytes);
    auto& payload = sections[5].payload;
    payload.clear();
    append(payload, static_cast<std::uint32_t>(copies));
    for (int c = 0; c < copies; ++c) {
      append(payload, from);
      append(payload, to);
      for (double v : {1.0, 0.0, 0.0, 0.0, 0.1, 0.0, 0.0}) append(payload, v);  // identity rotation, 10 cm
      for (int r = 0; r < 6; ++r)
        for (int col = r; col < 6; ++col) append(payload, r == col ? info_diag : 0.0);
    }
    return join_sections(a.bytes, kMapFileVersion, sections);
  };
  Map target;
  EXPECT_EQ(decode_error(with_link(4, 3, 1, 100.0), a.ctx, target), "");
  EXPECT_NE(decode_error(with_link(3, 3, 1, 100.0), a.ctx, target).find("depth link to itself"), std::string::npos);
  EXPECT_NE(decode_error(with_link(4, 3, 2, 100.0), a.ctx, target).find("two depth links"), std::string::npos);
  EXPECT_NE(decode_error(with_link(4, 99, 1, 100.0), a.ctx, target).find("unknown id 99"), std::string::npos);
  EXPECT_NE(decode_error(with_link(4, 3, 1, -1.0), a.ctx, target).find("negative diagonal"), std::string::npos);
  const std::string nan = decode_error(with_link(4, 3, 1, std::nan("")), a.ctx, target);
  EXPECT_NE(nan.find("DLNK"), std::string::npos) << nan;
  EXPECT_NE(nan.find("test.map"), std::string::npos) << nan;
  // The rejected files left the target map alone: it holds the one good file's map.
  std::lock_guard lock(target.mutex());
  EXPECT_EQ(target.keyframe_count(), 6u);
  EXPECT_EQ(target.keyframes()[4]->depth_link_to.lock()->id, 3);
}

// Plane landmarks (version 4): map planes with their observers, and each keyframe's measured
// planes with the map plane each joined, come back exactly; observers not in the map and
// measurements of a plane not in the map are not written; saving again gives the same bytes.
// A map extended after loading keeps numbering planes after the saved ones.
TEST(MapSerializer, PlaneLandmarksRoundTrip) {
  Built a(8, 60);
  {
    std::lock_guard lock(a.map.mutex());
    const auto kfs = a.map.keyframes();
    std::mt19937 rng(11);
    std::normal_distribution<double> g;
    for (int p = 0; p < 3; ++p) {
      auto pl = std::make_shared<MapPlane>();
      pl->id = a.map.next_plane_id();
      pl->n_w = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
      pl->d_w = g(rng);
      pl->last_seen_from = Eigen::Vector3d(g(rng), g(rng), g(rng));
      a.map.add_plane(pl);
    }
    const auto planes = a.map.planes();
    auto measure = [&](std::size_t k, const std::shared_ptr<MapPlane>& pl) {
      PlaneMeasurement m{Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized(), g(rng), static_cast<std::size_t>(600 + k)};
      kfs[k]->planes.push_back({m, pl});
      if (pl) pl->observers.push_back(kfs[k]);
    };
    measure(1, planes[0]);
    measure(1, planes[1]);
    measure(3, planes[0]);
    measure(6, planes[2]);
    measure(6, nullptr);  // measured, not associated
    // An observer culled from the map, and a measurement of a plane merged away (not in the map).
    planes[2]->observers.push_back(std::make_shared<KeyFrame>(99, Frame(99, 9.9, kfs[0]->f)));
    kfs[7]->planes.push_back({PlaneMeasurement{Eigen::Vector3d::UnitX(), 0.5, 700}, std::make_shared<MapPlane>()});
    a.bytes = encode_map(a.map, *a.ctx, 0);
  }
  Map loaded;
  std::lock_guard la(a.map.mutex());
  std::lock_guard lb(loaded.mutex());
  decode_map(a.bytes.data(), a.bytes.size(), "mem", loaded, a.ctx);
  const auto built = a.map.planes(), got = loaded.planes();
  ASSERT_EQ(got.size(), 3u);
  for (std::size_t p = 0; p < 3; ++p) {
    EXPECT_EQ(got[p]->id, built[p]->id);
    EXPECT_EQ(got[p]->n_w, built[p]->n_w);
    EXPECT_EQ(got[p]->d_w, built[p]->d_w);
    EXPECT_EQ(got[p]->last_seen_from, built[p]->last_seen_from);
  }
  auto observer_ids = [](const MapPlane& pl) {
    std::vector<long> ids;
    for (const auto& o : pl.observers) ids.push_back(o.lock()->id);
    return ids;
  };
  EXPECT_EQ(observer_ids(*got[0]), (std::vector<long>{1, 3}));
  EXPECT_EQ(observer_ids(*got[1]), (std::vector<long>{1}));
  EXPECT_EQ(observer_ids(*got[2]), (std::vector<long>{6}));  // the culled keyframe 99 is not saved
  const auto kb = loaded.keyframes(), ka = a.map.keyframes();
  for (std::size_t k = 0; k < kb.size(); ++k) {
    ASSERT_EQ(kb[k]->planes.size(), ka[k]->planes.size()) << "keyframe " << k;
    for (std::size_t j = 0; j < kb[k]->planes.size(); ++j) {
      const auto &x = ka[k]->planes[j], &y = kb[k]->planes[j];
      EXPECT_EQ(y.m.n_c, x.m.n_c);
      EXPECT_EQ(y.m.d_c, x.m.d_c);
      EXPECT_EQ(y.m.inliers, x.m.inliers);
      const bool saved_plane = x.landmark && std::count(built.begin(), built.end(), x.landmark);
      EXPECT_EQ(y.landmark ? y.landmark->id : -1, saved_plane ? x.landmark->id : -1) << "keyframe " << k;
      if (y.landmark) {
        EXPECT_EQ(y.landmark, got[static_cast<std::size_t>(y.landmark->id)]);  // the loaded map's own plane
      }
    }
  }
  EXPECT_EQ(loaded.peek_next_plane_id(), 3);
  // Saved again: the merged-away plane's measurement is now unassociated, as it was written.
  EXPECT_EQ(encode_map(loaded, *a.ctx, 0), a.bytes);
}

TEST(MapSerializer, BadPlaneLandmarksAreRejected) {
  Built a(6, 50);
  // One plane (id 0, observed by keyframe `observer`) and keyframe 2 measuring plane `measured`.
  auto with_planes = [&](std::int64_t next_id, std::int64_t id, int copies, double nx, std::int64_t observer,
                         std::int64_t measured) {
    auto sections = split_sections(a.bytes);
    auto& payload = sections[6].payload;
    payload.clear();
    append(payload, next_id);
    append(payload, static_cast<std::uint32_t>(copies));
    for (int c = 0; c < copies; ++c) {
      append(payload, id);
      for (double v : {nx, 0.0, 0.0, 0.7, 0.1, 0.2, 0.3}) append(payload, v);
      append(payload, static_cast<std::uint32_t>(1));
      append(payload, observer);
    }
    append(payload, static_cast<std::uint32_t>(1));
    append(payload, static_cast<std::int64_t>(2));
    append(payload, static_cast<std::uint32_t>(1));
    for (double v : {0.0, 1.0, 0.0, 1.2}) append(payload, v);
    append(payload, static_cast<std::uint64_t>(900));
    append(payload, measured);
    return join_sections(a.bytes, kMapFileVersion, sections);
  };
  Map target;
  EXPECT_EQ(decode_error(with_planes(1, 0, 1, 1.0, 2, 0), a.ctx, target), "");
  EXPECT_NE(decode_error(with_planes(1, 0, 2, 1.0, 2, 0), a.ctx, target).find("plane 0 appears twice"), std::string::npos);
  EXPECT_NE(decode_error(with_planes(1, 1, 1, 1.0, 2, 1), a.ctx, target).find("outside 0 to the next plane id"),
            std::string::npos);
  EXPECT_NE(decode_error(with_planes(1, 0, 1, 2.0, 2, 0), a.ctx, target).find("not a unit vector"), std::string::npos);
  EXPECT_NE(decode_error(with_planes(-1, 0, 0, 1.0, 2, -1), a.ctx, target).find("next plane id -1 is negative"),
            std::string::npos);
  EXPECT_NE(decode_error(with_planes(1, 0, 1, 1.0, 42, 0), a.ctx, target).find("unknown id 42"), std::string::npos);
  EXPECT_NE(decode_error(with_planes(1, 0, 1, 1.0, 2, 5), a.ctx, target).find("unknown id 5"), std::string::npos);
  const std::string nan = decode_error(with_planes(1, 0, 1, std::nan(""), 2, 0), a.ctx, target);
  EXPECT_NE(nan.find("PLAN"), std::string::npos) << nan;
  EXPECT_NE(nan.find("test.map"), std::string::npos) << nan;
  // The rejected files left the target map alone: it holds the one good file's map.
  std::lock_guard lock(target.mutex());
  ASSERT_EQ(target.planes().size(), 1u);
  EXPECT_EQ(target.planes()[0]->observers.size(), 1u);
  EXPECT_EQ(target.keyframes()[2]->planes.at(0).landmark, target.planes()[0]);
}

}  // namespace
}  // namespace builtscene::slam
