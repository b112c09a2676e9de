#include "slam/map_serializer.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include <fmt/format.h>
#include <zlib.h>

#include "core/errors.hpp"
#include "slam/key_frame.hpp"
#include "slam/map.hpp"
#include "slam/map_point.hpp"
#include "slam/plane_landmark.hpp"

namespace builtscene::slam {

static_assert(std::endian::native == std::endian::little, "map files are written in the host's byte order");

namespace {

constexpr char kMagic[8] = {'B', 'S', 'M', 'A', 'P', '\r', '\n', '\x1a'};
constexpr std::uint32_t kByteOrderMark = 0x01020304u;
constexpr std::size_t kHeaderSize = 48;
constexpr std::uint32_t tag(const char (&s)[5]) {
  return static_cast<std::uint32_t>(static_cast<unsigned char>(s[0])) |
         static_cast<std::uint32_t>(static_cast<unsigned char>(s[1])) << 8 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(s[2])) << 16 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(s[3])) << 24;
}
constexpr std::uint32_t kContextTag = tag("CTXT"), kKeyFramesTag = tag("KFRM"), kPointsTag = tag("MPTS"),
                        kCovisibilityTag = tag("COVI"), kLoopEdgesTag = tag("LOOP"), kDepthLinksTag = tag("DLNK"),
                        kPlanesTag = tag("PLAN");
// Version 2 added the loop edges, version 3 the depth links, version 4 the plane landmarks;
// older files still load.
constexpr std::uint32_t kSectionOrder[] = {kContextTag,   kKeyFramesTag,  kPointsTag, kCovisibilityTag,
                                           kLoopEdgesTag, kDepthLinksTag, kPlanesTag};
constexpr std::size_t section_count(std::uint32_t version) { return version >= 4 ? 7 : version == 3 ? 6 : version == 2 ? 5 : 4; }
constexpr std::size_t kMapPlaneBytes = 8 + 7 * 8 + 4;
constexpr std::size_t kPlaneMeasurementBytes = 4 * 8 + 8 + 8;
constexpr std::size_t kDepthLinkBytes = 16 + 7 * 8 + 21 * 8;
constexpr std::size_t kKeypointBytes = 7 * 4;

std::string tag_name(std::uint32_t t) {
  std::string s(4, ' ');
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((t >> (8 * i)) & 0xff);
    s[static_cast<std::size_t>(i)] = (c >= 32 && c < 127) ? c : '?';
  }
  return s;
}

class Writer {
 public:
  std::vector<std::uint8_t> bytes;
  template <typename T>
  void put(T v) {
    static_assert(std::is_trivially_copyable_v<T>);
    raw(&v, sizeof(T));
  }
  void raw(const void* data, std::size_t n) {
    if (n == 0) return;
    const std::size_t at = bytes.size();
    if (at + n > bytes.capacity()) bytes.reserve(std::max(2 * bytes.capacity(), at + n));
    bytes.resize(at + n);
    std::memcpy(bytes.data() + at, data, n);
  }
  void vec3(const Eigen::Vector3d& v) {
    for (int i = 0; i < 3; ++i) put(v[i]);
  }
  void pose(const SE3& T) {
    // SE3 normalizes its quaternion on construction; store one that normalization maps to
    // itself so that load -> save reproduces the bytes exactly.
    Eigen::Quaterniond q = T.rotation();
    for (int i = 0; i < 4; ++i) {
      const Eigen::Quaterniond n = q.normalized();
      if (n.coeffs() == q.coeffs()) break;
      q = n;
    }
    put(q.w());
    put(q.x());
    put(q.y());
    put(q.z());
    vec3(T.translation());
  }
  void keypoint(const cv::KeyPoint& k) {
    put(k.pt.x);
    put(k.pt.y);
    put(k.size);
    put(k.angle);
    put(k.response);
    put(static_cast<std::int32_t>(k.octave));
    put(static_cast<std::int32_t>(k.class_id));
  }
};

// Bounds-checked reading of one section; every failure names the file and section.
class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size, const std::string& file, std::string section)
      : p_(data), size_(size), file_(file), section_(std::move(section)) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(located(file_, 0, fmt::format("section {}: {}", section_, what)));
  }
  void need(std::size_t n, const char* what) const {
    if (n > size_ - pos_) fail(fmt::format("{} runs past the end of the section (offset {})", what, pos_));
  }
  template <typename T>
  T get(const char* what) {
    need(sizeof(T), what);
    T v;
    std::memcpy(&v, p_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  double finite(const char* what) {
    const double v = get<double>(what);
    if (!std::isfinite(v)) fail(fmt::format("{} is not a finite number", what));
    return v;
  }
  float finite_f(const char* what) {
    const float v = get<float>(what);
    if (!std::isfinite(v)) fail(fmt::format("{} is not a finite number", what));
    return v;
  }
  Eigen::Vector3d vec3(const char* what) {
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) v[i] = finite(what);
    return v;
  }
  SE3 pose(const char* what) {
    double c[4];
    for (double& x : c) x = finite(what);
    const Eigen::Quaterniond q(c[0], c[1], c[2], c[3]);
    if (std::abs(q.norm() - 1.0) > 1e-6) fail(fmt::format("{}: rotation is not a unit quaternion", what));
    const Eigen::Vector3d t = vec3(what);
    return SE3(q, t);
  }
  // A count of records each at least `min_bytes` long; rejects counts the section cannot hold.
  std::size_t count(std::size_t min_bytes, const char* what) {
    const auto n = get<std::uint32_t>(what);
    if (static_cast<std::uint64_t>(n) * std::max<std::size_t>(min_bytes, 1) > size_ - pos_)
      fail(fmt::format("{} {} cannot fit in the {} bytes left", what, n, size_ - pos_));
    return n;
  }
  const std::uint8_t* bytes(std::size_t n, const char* what) {
    need(n, what);
    const std::uint8_t* r = p_ + pos_;
    pos_ += n;
    return r;
  }
  void expect_end() const {
    if (pos_ != size_) fail(fmt::format("{} unexpected bytes at the end", size_ - pos_));
  }

 private:
  const std::uint8_t* p_;
  std::size_t size_, pos_ = 0;
  const std::string& file_;
  std::string section_;
};

struct ContextRecord {
  double fx, fy, cx, cy, k1, k2, p1, p2, k3, bf, th_depth;
  std::int32_t width, height, levels, descriptor_type, descriptor_cols, descriptor_kind;
  float scale_factor;
  std::int64_t next_kf_id, next_point_id;
};

void write_context(Writer& w, const FrameContext& ctx, const Map& map, int descriptor_type, int descriptor_cols) {
  const auto& c = ctx.camera;
  for (double v : {c.fx, c.fy, c.cx, c.cy, c.k1, c.k2, c.p1, c.p2, c.k3, ctx.bf, ctx.th_depth}) w.put(v);
  w.put(static_cast<std::int32_t>(c.width));
  w.put(static_cast<std::int32_t>(c.height));
  w.put(static_cast<std::int32_t>(ctx.pyramid.levels()));
  w.put(ctx.pyramid.scale_factor);
  w.put(static_cast<std::int32_t>(ctx.metric.kind == DescriptorKind::kBinary ? 0 : 1));
  w.put(static_cast<std::int32_t>(descriptor_type));
  w.put(static_cast<std::int32_t>(descriptor_cols));
  w.put(static_cast<std::int64_t>(map.peek_next_keyframe_id()));
  w.put(static_cast<std::int64_t>(map.peek_next_point_id()));
}

ContextRecord read_context(Reader& r) {
  ContextRecord c{};
  for (double* v : {&c.fx, &c.fy, &c.cx, &c.cy, &c.k1, &c.k2, &c.p1, &c.p2, &c.k3, &c.bf, &c.th_depth})
    *v = r.finite("camera parameter");
  c.width = r.get<std::int32_t>("image width");
  c.height = r.get<std::int32_t>("image height");
  c.levels = r.get<std::int32_t>("pyramid levels");
  c.scale_factor = r.finite_f("pyramid scale factor");
  c.descriptor_kind = r.get<std::int32_t>("descriptor kind");
  c.descriptor_type = r.get<std::int32_t>("descriptor type");
  c.descriptor_cols = r.get<std::int32_t>("descriptor width");
  c.next_kf_id = r.get<std::int64_t>("next keyframe id");
  c.next_point_id = r.get<std::int64_t>("next point id");
  r.expect_end();
  if (c.levels < 1 || c.levels > 32) r.fail(fmt::format("pyramid levels {} out of range", c.levels));
  if (c.descriptor_cols < 1 || c.descriptor_cols > 4096) r.fail(fmt::format("descriptor width {} out of range", c.descriptor_cols));
  if (c.descriptor_type != CV_8U && c.descriptor_type != CV_32F) r.fail("descriptor type is neither 8-bit nor float");
  if (c.next_kf_id < 0 || c.next_point_id < 0) r.fail("negative id counter");
  return c;
}

// The loaded map must have been built with the camera and features in use now: keypoints and
// scale ranges are in its pixels and pyramid.
void check_context_matches(const ContextRecord& c, const FrameContext& ctx, const std::string& file) {
  auto differ = [&](const char* what, double saved, double now) {
    if (std::abs(saved - now) > 1e-9 * std::max(1.0, std::abs(now)))
      throw InputError(located(file, 0, fmt::format("map was built with {} {} but the camera settings in use have {}",
                                                    what, saved, now)));
  };
  const auto& cam = ctx.camera;
  differ("Camera.fx", c.fx, cam.fx);
  differ("Camera.fy", c.fy, cam.fy);
  differ("Camera.cx", c.cx, cam.cx);
  differ("Camera.cy", c.cy, cam.cy);
  differ("Camera.k1", c.k1, cam.k1);
  differ("Camera.k2", c.k2, cam.k2);
  differ("Camera.p1", c.p1, cam.p1);
  differ("Camera.p2", c.p2, cam.p2);
  differ("Camera.k3", c.k3, cam.k3);
  differ("Camera.width", c.width, cam.width);
  differ("Camera.height", c.height, cam.height);
  differ("Camera.bf", c.bf, ctx.bf);
  differ("ORBextractor.nLevels", c.levels, ctx.pyramid.levels());
  differ("ORBextractor.scaleFactor", c.scale_factor, ctx.pyramid.scale_factor);
  const int kind = ctx.metric.kind == DescriptorKind::kBinary ? 0 : 1;
  if (c.descriptor_kind != kind)
    throw InputError(located(file, 0, fmt::format("map holds {} descriptors but the extractor in use makes {} ones",
                                                  c.descriptor_kind == 0 ? "binary" : "float", kind == 0 ? "binary" : "float")));
}

void section(Writer& out, std::uint32_t t, const Writer& payload) {
  out.put(t);
  out.put(map_file_crc32(payload.bytes.data(), payload.bytes.size()));
  out.put(static_cast<std::uint64_t>(payload.bytes.size()));
  out.raw(payload.bytes.data(), payload.bytes.size());
}

template <typename M>
typename M::mapped_type lookup(const M& m, long id, Reader& r, const std::string& what) {
  const auto it = m.find(id);
  if (it == m.end()) r.fail(fmt::format("{} refers to unknown id {}", what, id));
  return it->second;
}

}  // namespace

std::uint32_t map_file_crc32(const std::uint8_t* data, std::size_t size) {
  uLong crc = crc32(0L, Z_NULL, 0);
  // zlib takes uInt lengths; feed large buffers in pieces.
  while (size > 0) {
    const auto n = static_cast<uInt>(std::min<std::size_t>(size, 1u << 30));
    crc = crc32(crc, data, n);
    data += n;
    size -= n;
  }
  return static_cast<std::uint32_t>(crc);
}

std::vector<std::uint8_t> encode_map(const Map& map, const FrameContext& ctx, std::uint64_t vocabulary_checksum) {
  const auto keyframes = map.keyframes();
  const auto points = map.points();
  int descriptor_type = ctx.metric.kind == DescriptorKind::kBinary ? CV_8U : CV_32F;
  int descriptor_cols = ctx.metric.kind == DescriptorKind::kBinary ? 32 : 0;
  for (const auto& kf : keyframes) {
    if (kf->f->descriptors.rows > 0) {
      descriptor_type = kf->f->descriptors.type();
      descriptor_cols = kf->f->descriptors.cols;
      break;
    }
  }
  std::unordered_set<const MapPoint*> saved_points;
  for (const auto& p : points) saved_points.insert(p.get());
  std::unordered_set<const KeyFrame*> saved_kfs;
  for (const auto& kf : keyframes) saved_kfs.insert(kf.get());
  const std::size_t descriptor_bytes = static_cast<std::size_t>(descriptor_cols) * CV_ELEM_SIZE(descriptor_type);

  Writer context;
  write_context(context, ctx, map, descriptor_type, descriptor_cols);

  Writer kfw;
  std::size_t keypoints = 0;
  for (const auto& kf : keyframes) keypoints += kf->f->size();
  kfw.bytes.reserve(4 + keyframes.size() * 100 + keypoints * (kKeypointBytes + descriptor_bytes + 16));
  kfw.put(static_cast<std::uint32_t>(keyframes.size()));
  for (const auto& kf : keyframes) {
    const auto& f = *kf->f;
    kfw.put(static_cast<std::int64_t>(kf->id));
    kfw.put(static_cast<std::int64_t>(kf->frame_id));
    kfw.put(kf->timestamp);
    kfw.pose(kf->pose());
    const bool parent_saved = kf->parent && saved_kfs.count(kf->parent.get());
    kfw.put(static_cast<std::int64_t>(parent_saved ? kf->parent->id : -1));
    // Tree flags: bit 0 joined the tree, bit 1 through the depth-odometry bridge (readers
    // before bit 1 existed take any non-zero value as joined).
    kfw.put(static_cast<std::uint8_t>((kf->has_parent_link ? 1 : 0) | (kf->parent_by_odometry ? 2 : 0)));
    kfw.put(static_cast<std::uint8_t>(kf->keep));
    const std::size_t n = f.size();
    kfw.put(static_cast<std::uint32_t>(n));
    bool same = f.keys.size() == n;
    for (std::size_t i = 0; same && i < n; ++i)
      same = f.keys[i].pt == f.keys_un[i].pt && f.keys[i].octave == f.keys_un[i].octave &&
             f.keys[i].angle == f.keys_un[i].angle && f.keys[i].size == f.keys_un[i].size &&
             f.keys[i].response == f.keys_un[i].response && f.keys[i].class_id == f.keys_un[i].class_id;
    kfw.put(static_cast<std::uint8_t>(same));
    for (const auto& k : f.keys_un) kfw.keypoint(k);
    if (!same)
      for (const auto& k : f.keys) kfw.keypoint(k);
    if (n > 0) {
      if (f.descriptors.rows != static_cast<int>(n) || f.descriptors.type() != descriptor_type ||
          f.descriptors.cols != descriptor_cols)
        throw Failure(fmt::format("keyframe {}: descriptors differ in shape from the map's others; cannot save", kf->id));
      const cv::Mat d = f.descriptors.isContinuous() ? f.descriptors : f.descriptors.clone();
      kfw.raw(d.data, n * descriptor_bytes);
    }
    kfw.raw(f.depth.data(), n * sizeof(float));
    kfw.raw(f.u_right.data(), n * sizeof(float));
    for (std::size_t i = 0; i < n; ++i) {
      const auto& p = kf->points[i];
      kfw.put(static_cast<std::int64_t>(p && !p->bad && saved_points.count(p.get()) ? p->id : -1));
    }
  }

  Writer pw;
  pw.bytes.reserve(4 + points.size() * (92 + descriptor_bytes + 3 * 12));
  pw.put(static_cast<std::uint32_t>(points.size()));
  for (const auto& p : points) {
    pw.put(static_cast<std::int64_t>(p->id));
    pw.vec3(p->position);
    pw.vec3(p->normal);
    pw.put(p->min_distance);
    pw.put(p->max_distance);
    const bool ref_saved = p->reference && saved_kfs.count(p->reference);
    pw.put(static_cast<std::int64_t>(ref_saved ? p->reference->id : -1));
    pw.put(static_cast<std::int64_t>(p->created_by_kf));
    pw.put(static_cast<std::int32_t>(p->visible));
    pw.put(static_cast<std::int32_t>(p->found));
    if (p->descriptor.total() * p->descriptor.elemSize() == descriptor_bytes && p->descriptor.type() == descriptor_type) {
      const cv::Mat c = p->descriptor.isContinuous() ? p->descriptor : p->descriptor.clone();
      pw.raw(c.data, descriptor_bytes);
    } else {
      // A point without a representative descriptor yet: zeros, recomputed on load.
      std::vector<std::uint8_t> zeros(descriptor_bytes, 0);
      pw.raw(zeros.data(), descriptor_bytes);
    }
    std::vector<std::pair<long, std::int32_t>> obs;
    for (const auto& [kf, idx] : p->observations)
      if (saved_kfs.count(kf)) obs.emplace_back(kf->id, idx);
    std::sort(obs.begin(), obs.end());
    pw.put(static_cast<std::uint32_t>(obs.size()));
    for (const auto& [id, idx] : obs) {
      pw.put(static_cast<std::int64_t>(id));
      pw.put(idx);
    }
  }

  Writer cw;
  cw.put(static_cast<std::uint32_t>(keyframes.size()));
  for (const auto& kf : keyframes) {
    std::vector<std::pair<long, std::int32_t>> edges;
    for (const auto& [other, weight] : kf->connections)
      if (saved_kfs.count(other)) edges.emplace_back(other->id, weight);
    std::sort(edges.begin(), edges.end());
    cw.put(static_cast<std::int64_t>(kf->id));
    cw.put(static_cast<std::uint32_t>(edges.size()));
    for (const auto& [id, w] : edges) {
      cw.put(static_cast<std::int64_t>(id));
      cw.put(w);
    }
  }

  Writer lw;
  std::vector<std::pair<long, long>> loops;
  for (const auto& kf : keyframes)
    for (const KeyFrame* other : kf->loop_edges)
      if (saved_kfs.count(other) && kf->id < other->id) loops.emplace_back(kf->id, other->id);
  std::sort(loops.begin(), loops.end());
  lw.put(static_cast<std::uint32_t>(loops.size()));
  for (const auto& [a, b] : loops) {
    lw.put(static_cast<std::int64_t>(a));
    lw.put(static_cast<std::int64_t>(b));
  }

  // Depth links (TrackingOptions::depth_links): one per keyframe at most, to an older one;
  // the information matrix is symmetric, so only its upper triangle is stored.
  Writer dw;
  std::vector<const KeyFrame*> linked;
  for (const auto& kf : keyframes) {
    const auto to = kf->depth_link_to.lock();
    if (to && !to->bad && saved_kfs.count(to.get())) linked.push_back(kf.get());
  }
  dw.put(static_cast<std::uint32_t>(linked.size()));
  for (const KeyFrame* kf : linked) {  // keyframes() is in id order
    dw.put(static_cast<std::int64_t>(kf->id));
    dw.put(static_cast<std::int64_t>(kf->depth_link_to.lock()->id));
    dw.pose(kf->depth_link_T);
    for (int r = 0; r < 6; ++r)
      for (int c = r; c < 6; ++c) dw.put(kf->depth_link_information(r, c));
  }

  // Plane landmarks (plane_landmark.hpp): the next plane id; the map planes by id, each with
  // n_w, d_w, last_seen_from and its saved observers in the order they joined; then per
  // keyframe with measured planes its measurements (n_c, d_c, inliers, map plane id or -1).
  Writer plw;
  plw.put(static_cast<std::int64_t>(map.peek_next_plane_id()));
  auto planes = map.planes();
  std::sort(planes.begin(), planes.end(), [](const auto& a, const auto& b) { return a->id < b->id; });
  std::unordered_set<const MapPlane*> saved_planes;
  plw.put(static_cast<std::uint32_t>(planes.size()));
  for (const auto& pl : planes) {
    saved_planes.insert(pl.get());
    plw.put(static_cast<std::int64_t>(pl->id));
    for (int i = 0; i < 3; ++i) plw.put(pl->n_w[i]);
    plw.put(pl->d_w);
    for (int i = 0; i < 3; ++i) plw.put(pl->last_seen_from[i]);
    std::vector<long> observers;
    for (const auto& o : pl->observers)
      if (const auto k = o.lock(); k && saved_kfs.count(k.get())) observers.push_back(k->id);
    plw.put(static_cast<std::uint32_t>(observers.size()));
    for (long id : observers) plw.put(static_cast<std::int64_t>(id));
  }
  std::vector<const KeyFrame*> measuring;
  for (const auto& kf : keyframes)
    if (!kf->planes.empty()) measuring.push_back(kf.get());
  plw.put(static_cast<std::uint32_t>(measuring.size()));
  for (const KeyFrame* kf : measuring) {
    plw.put(static_cast<std::int64_t>(kf->id));
    plw.put(static_cast<std::uint32_t>(kf->planes.size()));
    for (const auto& kp : kf->planes) {
      for (int i = 0; i < 3; ++i) plw.put(kp.m.n_c[i]);
      plw.put(kp.m.d_c);
      plw.put(static_cast<std::uint64_t>(kp.m.inliers));
      plw.put(static_cast<std::int64_t>(kp.landmark && saved_planes.count(kp.landmark.get()) ? kp.landmark->id : -1));
    }
  }

  const std::size_t body_size = 7 * 16 + context.bytes.size() + kfw.bytes.size() + pw.bytes.size() +
                                cw.bytes.size() + lw.bytes.size() + dw.bytes.size() + plw.bytes.size();
  Writer out;
  out.bytes.reserve(kHeaderSize + body_size);
  out.raw(kMagic, sizeof(kMagic));
  out.put(kMapFileVersion);
  out.put(kByteOrderMark);
  out.put(vocabulary_checksum);
  out.put(static_cast<std::uint32_t>(std::size(kSectionOrder)));
  out.put(static_cast<std::uint32_t>(0));
  out.put(static_cast<std::uint64_t>(body_size));
  out.put(map_file_crc32(out.bytes.data(), out.bytes.size()));
  out.put(static_cast<std::uint32_t>(0));
  section(out, kContextTag, context);
  section(out, kKeyFramesTag, kfw);
  section(out, kPointsTag, pw);
  section(out, kCovisibilityTag, cw);
  section(out, kLoopEdgesTag, lw);
  section(out, kDepthLinksTag, dw);
  section(out, kPlanesTag, plw);
  return std::move(out.bytes);
}

MapFileInfo decode_map(const std::uint8_t* data, std::size_t size, const std::string& name, Map& map,
                       const std::shared_ptr<const FrameContext>& ctx, std::optional<std::uint64_t> vocabulary_checksum) {
  auto fail = [&](const std::string& what) -> void { throw InputError(located(name, 0, what)); };
  if (size < sizeof(kMagic) || std::memcmp(data, kMagic, sizeof(kMagic)) != 0)
    fail("not a builtscene map file (no BSMAP signature at the start)");
  if (size < kHeaderSize) fail(fmt::format("truncated map file: {} bytes, shorter than the {}-byte header", size, kHeaderSize));
  Reader h(data, kHeaderSize, name, "header");
  h.bytes(sizeof(kMagic), "magic");
  const auto version = h.get<std::uint32_t>("version");
  const auto order = h.get<std::uint32_t>("byte-order mark");
  const auto vocabulary = h.get<std::uint64_t>("vocabulary checksum");
  const auto sections = h.get<std::uint32_t>("section count");
  const auto reserved1 = h.get<std::uint32_t>("reserved");
  const auto body_size = h.get<std::uint64_t>("body size");
  const auto header_crc = h.get<std::uint32_t>("header checksum");
  const auto reserved2 = h.get<std::uint32_t>("reserved");
  if (order == 0x04030201u) fail("map file was written with the other byte order (big-endian); not supported");
  if (header_crc != map_file_crc32(data, 40)) fail("header checksum mismatch: the file is corrupt");
  if (order != kByteOrderMark || reserved1 != 0 || reserved2 != 0) fail("header fields are invalid: the file is corrupt");
  if (version < 1 || version > kMapFileVersion)
    fail(fmt::format("map file version {} is not supported (this build reads versions 1 to {})", version, kMapFileVersion));
  if (vocabulary_checksum && vocabulary != 0 && vocabulary != *vocabulary_checksum)
    fail(fmt::format("map was saved with vocabulary checksum {:016x}, but the vocabulary in use has {:016x}; "
                     "use the map with the vocabulary it was built with",
                     vocabulary, *vocabulary_checksum));
  const std::size_t n_sections = section_count(version);
  if (sections != n_sections) fail(fmt::format("header lists {} sections, expected {} for version {}", sections, n_sections, version));
  if (body_size > size - kHeaderSize)
    fail(fmt::format("truncated map file: header announces {} bytes of sections, only {} present", body_size, size - kHeaderSize));
  if (body_size < size - kHeaderSize) fail(fmt::format("{} unexpected bytes after the last section", size - kHeaderSize - body_size));

  // Section table: verify every checksum before interpreting anything.
  struct Span {
    const std::uint8_t* data;
    std::size_t size;
  };
  std::vector<Span> spans;
  std::size_t pos = kHeaderSize;
  for (std::size_t si = 0; si < n_sections; ++si) {
    const std::uint32_t expected = kSectionOrder[si];
    if (size - pos < 16) fail(fmt::format("truncated map file: section {} header missing at offset {}", tag_name(expected), pos));
    std::uint32_t t, crc;
    std::uint64_t n;
    std::memcpy(&t, data + pos, 4);
    std::memcpy(&crc, data + pos + 4, 4);
    std::memcpy(&n, data + pos + 8, 8);
    pos += 16;
    if (t != expected) fail(fmt::format("expected section {} at offset {}, found '{}'", tag_name(expected), pos - 16, tag_name(t)));
    if (n > size - pos) fail(fmt::format("truncated map file: section {} needs {} bytes, {} left", tag_name(t), n, size - pos));
    if (map_file_crc32(data + pos, n) != crc) fail(fmt::format("section {}: checksum mismatch: the file is corrupt", tag_name(t)));
    spans.push_back({data + pos, n});
    pos += n;
  }

  Reader cr(spans[0].data, spans[0].size, name, "CTXT");
  const ContextRecord c = read_context(cr);
  check_context_matches(c, *ctx, name);
  const std::size_t descriptor_bytes = static_cast<std::size_t>(c.descriptor_cols) * CV_ELEM_SIZE(c.descriptor_type);

  // Keyframes.
  Reader kr(spans[1].data, spans[1].size, name, "KFRM");
  const std::size_t n_kfs = kr.count(80, "keyframe count");
  std::vector<std::shared_ptr<KeyFrame>> kfs;
  std::unordered_map<long, KeyFrame*> kf_by_id;
  std::vector<long> parent_ids;
  std::vector<std::uint8_t> parent_links;
  std::vector<std::vector<std::int64_t>> point_ids;
  kfs.reserve(n_kfs);
  for (std::size_t k = 0; k < n_kfs; ++k) {
    const long id = kr.get<std::int64_t>("keyframe id");
    const long frame_id = kr.get<std::int64_t>("frame id");
    const double timestamp = kr.finite("timestamp");
    const SE3 T_cw = kr.pose("keyframe pose");
    const long parent = kr.get<std::int64_t>("parent id");
    const auto link = kr.get<std::uint8_t>("tree flag");
    const auto keep = kr.get<std::uint8_t>("keep flag");
    if (id < 0 || id >= c.next_kf_id) kr.fail(fmt::format("keyframe id {} outside 0..{}", id, c.next_kf_id - 1));
    if (kf_by_id.count(id)) kr.fail(fmt::format("keyframe id {} appears twice", id));
    const std::size_t n = kr.count(kKeypointBytes + descriptor_bytes + 16, "keypoint count");
    const bool same = kr.get<std::uint8_t>("distortion flag") != 0;
    auto f = std::make_shared<FrameFeatures>();
    f->ctx = ctx;
    auto read_keys = [&](std::vector<cv::KeyPoint>& keys) {
      keys.resize(n);
      for (auto& kp : keys) {
        kp.pt.x = kr.finite_f("keypoint x");
        kp.pt.y = kr.finite_f("keypoint y");
        kp.size = kr.finite_f("keypoint size");
        kp.angle = kr.finite_f("keypoint angle");
        kp.response = kr.finite_f("keypoint response");
        kp.octave = kr.get<std::int32_t>("keypoint level");
        kp.class_id = kr.get<std::int32_t>("keypoint class");
        if (kp.octave < 0 || kp.octave >= c.levels)
          kr.fail(fmt::format("keyframe {}: keypoint level {} outside 0..{}", id, kp.octave, c.levels - 1));
      }
    };
    read_keys(f->keys_un);
    if (same) f->keys = f->keys_un;
    else read_keys(f->keys);
    f->descriptors.create(static_cast<int>(n), c.descriptor_cols, c.descriptor_type);
    if (n > 0) std::memcpy(f->descriptors.data, kr.bytes(n * descriptor_bytes, "descriptors"), n * descriptor_bytes);
    f->depth.resize(n);
    f->u_right.resize(n);
    if (n > 0) {
      std::memcpy(f->depth.data(), kr.bytes(n * 4, "depths"), n * 4);
      std::memcpy(f->u_right.data(), kr.bytes(n * 4, "right coordinates"), n * 4);
    }
    for (std::size_t i = 0; i < n; ++i)
      if (std::isnan(f->depth[i]) || std::isnan(f->u_right[i])) kr.fail(fmt::format("keyframe {}: depth is NaN", id));
    std::vector<std::int64_t> pids(n);
    if (n > 0) std::memcpy(pids.data(), kr.bytes(n * 8, "point ids"), n * 8);
    build_feature_grid(*f);
    Frame frame(frame_id, timestamp, f);
    frame.set_pose(T_cw);
    auto kf = std::make_shared<KeyFrame>(id, frame);
    kf->keep = keep != 0;
    kf_by_id[id] = kf.get();
    kfs.push_back(std::move(kf));
    parent_ids.push_back(parent);
    parent_links.push_back(link);
    point_ids.push_back(std::move(pids));
  }
  kr.expect_end();
  for (std::size_t k = 0; k < kfs.size(); ++k) {
    auto& kf = kfs[k];
    kf->has_parent_link = parent_links[k] != 0;
    kf->parent_by_odometry = (parent_links[k] & 2) != 0;
    if (parent_ids[k] < 0) continue;
    if (parent_ids[k] == kf->id) kr.fail(fmt::format("keyframe {} is its own parent", kf->id));
    KeyFrame* parent = lookup(kf_by_id, parent_ids[k], kr, fmt::format("keyframe {}'s parent", kf->id));
    kf->parent = parent->shared_from_this();
    parent->children.insert(kf.get());
  }
  // The spanning tree must be a tree: walking up from any keyframe ends at a root.
  for (const auto& kf : kfs) {
    const KeyFrame* k = kf.get();
    for (std::size_t steps = 0; k->parent; ++steps) {
      if (steps > kfs.size()) kr.fail(fmt::format("keyframe {}: the spanning tree has a cycle", kf->id));
      k = k->parent.get();
    }
  }

  // Map points.
  Reader pr(spans[2].data, spans[2].size, name, "MPTS");
  const std::size_t n_points = pr.count(92 + descriptor_bytes, "point count");
  std::vector<std::shared_ptr<MapPoint>> pts;
  std::unordered_map<long, std::shared_ptr<MapPoint>> point_by_id;
  pts.reserve(n_points);
  point_by_id.reserve(n_points);
  for (std::size_t k = 0; k < n_points; ++k) {
    const long id = pr.get<std::int64_t>("point id");
    if (id < 0 || id >= c.next_point_id) pr.fail(fmt::format("point id {} outside 0..{}", id, c.next_point_id - 1));
    if (point_by_id.count(id)) pr.fail(fmt::format("point id {} appears twice", id));
    const Eigen::Vector3d position = pr.vec3("point position");
    const Eigen::Vector3d normal = pr.vec3("point normal");
    const float min_d = pr.finite_f("point min distance"), max_d = pr.finite_f("point max distance");
    const long ref = pr.get<std::int64_t>("point reference keyframe");
    const long created = pr.get<std::int64_t>("point creator");
    const int visible = pr.get<std::int32_t>("point visible count");
    const int found = pr.get<std::int32_t>("point found count");
    KeyFrame* reference = ref < 0 ? nullptr : lookup(kf_by_id, ref, pr, fmt::format("point {}'s reference", id));
    auto p = std::make_shared<MapPoint>(id, position, reference, created);
    p->normal = normal;
    p->min_distance = min_d;
    p->max_distance = max_d;
    p->visible = visible;
    p->found = found;
    p->descriptor.create(1, c.descriptor_cols, c.descriptor_type);
    std::memcpy(p->descriptor.data, pr.bytes(descriptor_bytes, "point descriptor"), descriptor_bytes);
    const std::size_t n_obs = pr.count(12, "observation count");
    for (std::size_t o = 0; o < n_obs; ++o) {
      const long kf_id = pr.get<std::int64_t>("observation keyframe");
      const int idx = pr.get<std::int32_t>("observation keypoint");
      KeyFrame* kf = lookup(kf_by_id, kf_id, pr, fmt::format("point {}'s observation", id));
      if (idx < 0 || static_cast<std::size_t>(idx) >= kf->f->size())
        pr.fail(fmt::format("point {}: keypoint {} out of range in keyframe {}", id, idx, kf_id));
      if (p->observations.count(kf)) pr.fail(fmt::format("point {}: keyframe {} observes it twice", id, kf_id));
      p->add_observation(kf, idx);
    }
    point_by_id[id] = p;
    pts.push_back(std::move(p));
  }
  pr.expect_end();
  for (std::size_t k = 0; k < kfs.size(); ++k) {
    for (std::size_t i = 0; i < point_ids[k].size(); ++i) {
      const long pid = point_ids[k][i];
      if (pid < 0) continue;
      kfs[k]->points[i] = lookup(point_by_id, pid, kr, fmt::format("keyframe {} keypoint {}", kfs[k]->id, i));
    }
  }

  // Covisibility.
  Reader vr(spans[3].data, spans[3].size, name, "COVI");
  const std::size_t n_lists = vr.count(12, "covisibility list count");
  if (n_lists != kfs.size()) vr.fail(fmt::format("{} covisibility lists for {} keyframes", n_lists, kfs.size()));
  for (std::size_t k = 0; k < n_lists; ++k) {
    const long id = vr.get<std::int64_t>("keyframe id");
    KeyFrame* kf = lookup(kf_by_id, id, vr, "covisibility list");
    const std::size_t n = vr.count(12, "edge count");
    for (std::size_t e = 0; e < n; ++e) {
      const long other_id = vr.get<std::int64_t>("edge keyframe");
      const int weight = vr.get<std::int32_t>("edge weight");
      KeyFrame* other = lookup(kf_by_id, other_id, vr, fmt::format("keyframe {}'s covisibility edge", id));
      if (other == kf) vr.fail(fmt::format("keyframe {} is covisible with itself", id));
      if (weight <= 0) vr.fail(fmt::format("keyframe {}: edge weight {} is not positive", id, weight));
      kf->connections[other] = weight;
    }
  }
  vr.expect_end();
  std::vector<std::pair<KeyFrame*, KeyFrame*>> loop_edges;
  if (version >= 2) {
    Reader lr(spans[4].data, spans[4].size, name, "LOOP");
    const std::size_t n_loops = lr.count(16, "loop edge count");
    std::set<std::pair<long, long>> seen;
    for (std::size_t e = 0; e < n_loops; ++e) {
      const long a = lr.get<std::int64_t>("loop edge keyframe");
      const long b = lr.get<std::int64_t>("loop edge keyframe");
      KeyFrame* ka = lookup(kf_by_id, a, lr, "loop edge");
      KeyFrame* kb = lookup(kf_by_id, b, lr, "loop edge");
      if (ka == kb) lr.fail(fmt::format("keyframe {} has a loop edge to itself", a));
      if (!seen.insert({std::min(a, b), std::max(a, b)}).second) lr.fail(fmt::format("loop edge {}-{} appears twice", a, b));
      loop_edges.emplace_back(ka, kb);
    }
    lr.expect_end();
  }
  struct DepthLink {
    KeyFrame* from;
    KeyFrame* to;
    SE3 T;
    Eigen::Matrix<double, 6, 6> information;
  };
  std::vector<DepthLink> depth_links;
  if (version >= 3) {
    Reader dr(spans[5].data, spans[5].size, name, "DLNK");
    const std::size_t n_links = dr.count(kDepthLinkBytes, "depth link count");
    std::unordered_set<long> linked;
    for (std::size_t e = 0; e < n_links; ++e) {
      const long a = dr.get<std::int64_t>("depth link keyframe");
      const long b = dr.get<std::int64_t>("depth link target");
      KeyFrame* ka = lookup(kf_by_id, a, dr, "depth link");
      KeyFrame* kb = lookup(kf_by_id, b, dr, fmt::format("keyframe {}'s depth link", a));
      if (ka == kb) dr.fail(fmt::format("keyframe {} has a depth link to itself", a));
      if (!linked.insert(a).second) dr.fail(fmt::format("keyframe {} has two depth links", a));
      DepthLink link{ka, kb, dr.pose("depth link pose"), Eigen::Matrix<double, 6, 6>::Zero()};
      for (int r = 0; r < 6; ++r)
        for (int c = r; c < 6; ++c) link.information(r, c) = link.information(c, r) = dr.finite("depth link information");
      if ((link.information.diagonal().array() < 0).any())
        dr.fail(fmt::format("keyframe {}: depth link information has a negative diagonal entry", a));
      depth_links.push_back(link);
    }
    dr.expect_end();
  }
  std::vector<std::shared_ptr<MapPlane>> planes;
  std::vector<std::pair<KeyFrame*, std::vector<KeyFramePlane>>> keyframe_planes;
  long next_plane_id = 0;
  if (version >= 4) {
    Reader plr(spans[6].data, spans[6].size, name, "PLAN");
    next_plane_id = plr.get<std::int64_t>("next plane id");
    if (next_plane_id < 0) plr.fail(fmt::format("next plane id {} is negative", next_plane_id));
    const std::size_t n_planes = plr.count(kMapPlaneBytes, "plane count");
    std::unordered_map<long, std::shared_ptr<MapPlane>> plane_by_id;
    auto unit = [&](Reader& r, const char* what, const std::string& whose) {
      const Eigen::Vector3d n = r.vec3(what);
      if (std::abs(n.norm() - 1.0) > 1e-6) r.fail(fmt::format("{}: {} is not a unit vector", whose, what));
      return n;
    };
    for (std::size_t i = 0; i < n_planes; ++i) {
      auto pl = std::make_shared<MapPlane>();
      pl->id = plr.get<std::int64_t>("plane id");
      if (pl->id < 0 || pl->id >= next_plane_id)
        plr.fail(fmt::format("plane id {} is outside 0 to the next plane id {}", pl->id, next_plane_id));
      if (plane_by_id.count(pl->id)) plr.fail(fmt::format("plane {} appears twice", pl->id));
      pl->n_w = unit(plr, "plane normal", fmt::format("plane {}", pl->id));
      pl->d_w = plr.finite("plane offset");
      pl->last_seen_from = plr.vec3("plane last seen from");
      const std::size_t n_obs = plr.count(8, "plane observer count");
      std::unordered_set<long> seen;
      for (std::size_t o = 0; o < n_obs; ++o) {
        const long kid = plr.get<std::int64_t>("plane observer");
        KeyFrame* k = lookup(kf_by_id, kid, plr, fmt::format("plane {}'s observer", pl->id));
        if (!seen.insert(kid).second) plr.fail(fmt::format("plane {}: keyframe {} observes it twice", pl->id, kid));
        pl->observers.push_back(k->shared_from_this());
      }
      plane_by_id[pl->id] = pl;
      planes.push_back(pl);
    }
    const std::size_t n_measuring = plr.count(12, "measuring keyframe count");
    std::unordered_set<long> measured;
    for (std::size_t i = 0; i < n_measuring; ++i) {
      const long kid = plr.get<std::int64_t>("measuring keyframe");
      KeyFrame* k = lookup(kf_by_id, kid, plr, "plane measurements");
      if (!measured.insert(kid).second) plr.fail(fmt::format("keyframe {}'s plane measurements appear twice", kid));
      const std::size_t n_m = plr.count(kPlaneMeasurementBytes, "plane measurement count");
      std::vector<KeyFramePlane> list;
      for (std::size_t j = 0; j < n_m; ++j) {
        KeyFramePlane kp;
        kp.m.n_c = unit(plr, "measured plane normal", fmt::format("keyframe {}", kid));
        kp.m.d_c = plr.finite("measured plane offset");
        kp.m.inliers = static_cast<std::size_t>(plr.get<std::uint64_t>("measured plane inliers"));
        const long pid = plr.get<std::int64_t>("measured plane's map plane");
        if (pid >= 0) kp.landmark = lookup(plane_by_id, pid, plr, fmt::format("keyframe {}'s plane measurement", kid));
        list.push_back(std::move(kp));
      }
      keyframe_planes.emplace_back(k, std::move(list));
    }
    plr.expect_end();
  }
  for (auto& [kf, list] : keyframe_planes) kf->planes = std::move(list);
  for (const auto& [a, b] : loop_edges) {
    a->loop_edges.insert(b);
    b->loop_edges.insert(a);
  }
  for (const auto& l : depth_links) {
    l.from->depth_link_to = l.to->shared_from_this();
    l.from->depth_link_T = l.T;
    l.from->depth_link_information = l.information;
  }
  for (auto& kf : kfs) {
    // Rebuild the weight order through the one place that defines it.
    auto edges = kf->connections;
    kf->connections.clear();
    for (const auto& [other, w] : edges) kf->add_connection(other, w);
  }

  // Everything checked: replace the map's content.
  map.clear();
  for (auto& kf : kfs) map.add_keyframe(kf);
  for (auto& p : pts) map.add_point(p);
  for (auto& pl : planes) map.add_plane(pl);
  map.set_next_ids(c.next_kf_id, c.next_point_id);
  map.set_next_plane_id(next_plane_id);
  MapFileInfo info;
  info.version = version;
  info.vocabulary_checksum = vocabulary;
  info.keyframes = kfs.size();
  info.points = pts.size();
  info.bytes = size;
  return info;
}

MapFileInfo write_map_file(const std::filesystem::path& path, const Map& map, const FrameContext& ctx,
                           std::uint64_t vocabulary_checksum) {
  std::vector<std::uint8_t> bytes;
  MapFileInfo info;
  {
    std::lock_guard lock(map.mutex());
    bytes = encode_map(map, ctx, vocabulary_checksum);
    info.keyframes = map.keyframe_count();
    info.points = map.point_count();
  }
  auto tmp = path;
  tmp += ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(located(path, 0, "cannot write map file"));
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) throw InputError(located(path, 0, "writing the map file failed (disk full?)"));
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw InputError(located(path, 0, "cannot move the finished map into place: " + ec.message()));
  info.version = kMapFileVersion;
  info.vocabulary_checksum = vocabulary_checksum;
  info.bytes = bytes.size();
  return info;
}

MapFileInfo read_map_file(const std::filesystem::path& path, Map& map, const std::shared_ptr<const FrameContext>& ctx,
                          std::optional<std::uint64_t> vocabulary_checksum) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(located(path, 0, "map file not found"));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(located(path, 0, "cannot open map file"));
  in.seekg(0, std::ios::end);
  const auto size = static_cast<std::size_t>(in.tellg());
  in.seekg(0);
  std::vector<std::uint8_t> bytes(size);
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size));
  if (!in) throw InputError(located(path, 0, "cannot read map file"));
  std::lock_guard lock(map.mutex());
  return decode_map(bytes.data(), bytes.size(), path.string(), map, ctx, vocabulary_checksum);
}

}  // namespace builtscene::slam
