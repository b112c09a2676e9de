#include "ogm/occupancy_grid_mapper.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>

#include "core/checksum.hpp"
#include "core/errors.hpp"

namespace builtscene {
namespace {

double logit(double p) { return std::log(p / (1.0 - p)); }

constexpr char kStateMagic[8] = {'B', 'S', 'O', 'G', 'M', 'A', 'P', '\0'};
constexpr std::uint32_t kStateVersion = 1;

template <typename T>
void put(std::string& buf, const T& v) {
  buf.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

template <typename T>
T take(const std::string& buf, std::size_t& pos, const std::filesystem::path& path) {
  if (pos + sizeof(T) > buf.size()) throw_input_error(path, 0, "map state is truncated");
  T v;
  std::memcpy(&v, buf.data() + pos, sizeof(T));
  pos += sizeof(T);
  return v;
}

}  // namespace

OccupancyGridMapper::OccupancyGridMapper(OccupancyMapperOptions options) : options_(options) {
  if (!(options_.resolution > 0)) throw InputError("occupancy grid: resolution must be positive");
}

void OccupancyGridMapper::clear() {
  width_ = height_ = 0;
  evidence_.clear();
  stamp_.clear();
  hit_.clear();
  scans_ = 0;
}

void OccupancyGridMapper::integrate_batch(const std::vector<PoseAndScan>& batch) {
  if (batch.size() > 1) clear();
  for (const auto& p : batch) integrate(p);
}

void OccupancyGridMapper::ensure_contains(double x0, double y0, double x1, double y1) {
  const double res = options_.resolution;
  if (width_ > 0) {
    const double gx1 = origin_.x() + width_ * res, gy1 = origin_.y() + height_ * res;
    if (x0 >= origin_.x() && y0 >= origin_.y() && x1 < gx1 && y1 < gy1) return;
    x0 = std::min(x0, origin_.x());
    y0 = std::min(y0, origin_.y());
    x1 = std::max(x1, gx1);
    y1 = std::max(y1, gy1);
  }
  const double m = options_.grow_margin;
  // New origin on the old lattice so that existing cells keep their places.
  const Eigen::Vector2d anchor = width_ > 0 ? origin_ : Eigen::Vector2d(0, 0);
  const double nx0 = anchor.x() + std::floor((x0 - m - anchor.x()) / res) * res;
  const double ny0 = anchor.y() + std::floor((y0 - m - anchor.y()) / res) * res;
  const int nw = static_cast<int>(std::ceil((x1 + m - nx0) / res));
  const int nh = static_cast<int>(std::ceil((y1 + m - ny0) / res));
  std::vector<float> ev(static_cast<std::size_t>(nw) * static_cast<std::size_t>(nh), std::numeric_limits<float>::quiet_NaN());
  const int dc = static_cast<int>(std::lround((origin_.x() - nx0) / res));
  const int dr = static_cast<int>(std::lround((origin_.y() - ny0) / res));
  for (int r = 0; r < height_; ++r)
    for (int c = 0; c < width_; ++c)
      ev[static_cast<std::size_t>(r + dr) * static_cast<std::size_t>(nw) + static_cast<std::size_t>(c + dc)] = evidence_[index(c, r)];
  evidence_ = std::move(ev);
  width_ = nw;
  height_ = nh;
  origin_ = {nx0, ny0};
  stamp_.assign(evidence_.size(), 0);
  hit_.assign(evidence_.size(), 0);
}

void OccupancyGridMapper::apply(std::size_t i, bool occupied) {
  float& e = evidence_[i];
  if (options_.model == OccupancyMapperOptions::Model::kSource) {
    if (std::isnan(e)) e = 50.0f;
    e = static_cast<float>(std::clamp(e + (occupied ? options_.l_occ : -options_.l_free), 0.0, 100.0));
  } else {
    if (std::isnan(e)) e = 0.0f;
    const double lmax = logit(options_.p_clamp);
    e = static_cast<float>(std::clamp(e + (occupied ? logit(options_.p_occ) : logit(options_.p_free)), -lmax, lmax));
  }
}

void OccupancyGridMapper::integrate(const PoseAndScan& pair) {
  const auto& s = pair.scan;
  const auto& p = pair.pose;
  // Beam ends in the ground frame; the grid must hold all of them and the robot.
  std::vector<Eigen::Vector2d> ends;
  std::vector<bool> is_hit;
  double x0 = p.x, y0 = p.y, x1 = p.x, y1 = p.y;
  for (std::size_t i = 0; i < s.ranges.size(); ++i) {
    if (!s.valid(i)) continue;  // no return (inf) or outside the valid range: no evidence
    const double a = p.theta + s.beam_angle(i);
    const Eigen::Vector2d e(p.x + s.ranges[i] * std::cos(a), p.y + s.ranges[i] * std::sin(a));
    ends.push_back(e);
    is_hit.push_back(s.ranges[i] < s.range_max);
    x0 = std::min(x0, e.x());
    y0 = std::min(y0, e.y());
    x1 = std::max(x1, e.x());
    y1 = std::max(y1, e.y());
  }
  ++scans_;
  if (ends.empty()) return;
  ensure_contains(x0, y0, x1, y1);
  const auto stamp = static_cast<std::uint32_t>(scans_);
  const double res = options_.resolution;
  auto cell = [&](const Eigen::Vector2d& q) {
    return GridIndex{static_cast<int>(std::floor((q.x() - origin_.x()) / res)),
                     static_cast<int>(std::floor((q.y() - origin_.y()) / res))};
  };
  std::vector<std::size_t> touched;
  for (std::size_t k = 0; k < ends.size(); ++k) {
    if (!is_hit[k]) continue;
    const auto c = cell(ends[k]);
    const std::size_t i = index(c.col, c.row);
    if (stamp_[i] == stamp) continue;
    stamp_[i] = stamp;
    hit_[i] = 1;
    touched.push_back(i);
  }
  const GridIndex start = cell({p.x, p.y});
  for (std::size_t k = 0; k < ends.size(); ++k) {
    const auto line = bresenham_line(start, cell(ends[k]));
    const std::size_t n = is_hit[k] ? line.size() - 1 : line.size();  // the end cell of a hit is not free
    for (std::size_t j = 0; j < n; ++j) {
      const std::size_t i = index(line[j].col, line[j].row);
      if (stamp_[i] == stamp) continue;
      stamp_[i] = stamp;
      hit_[i] = 0;
      touched.push_back(i);
    }
  }
  for (std::size_t i : touched) apply(i, hit_[i] != 0);
}

OccupancyGrid OccupancyGridMapper::grid() const {
  OccupancyGrid g(width_, height_, options_.resolution, origin_);
  auto& d = g.data();
  for (std::size_t i = 0; i < evidence_.size(); ++i) {
    const float e = evidence_[i];
    if (std::isnan(e)) continue;
    if (options_.model == OccupancyMapperOptions::Model::kSource) {
      d[i] = static_cast<std::int8_t>(std::lround(e));
    } else {
      d[i] = static_cast<std::int8_t>(std::lround(100.0 / (1.0 + std::exp(-e))));
    }
  }
  return g;
}

void OccupancyGridMapper::save_state(const std::filesystem::path& path) const {
  std::string payload;
  put(payload, static_cast<std::uint32_t>(options_.model));
  for (double v : {options_.resolution, options_.l_free, options_.l_occ, options_.p_free, options_.p_occ,
                   options_.p_clamp, options_.grow_margin, origin_.x(), origin_.y()})
    put(payload, v);
  put(payload, static_cast<std::int32_t>(width_));
  put(payload, static_cast<std::int32_t>(height_));
  put(payload, static_cast<std::uint64_t>(scans_));
  payload.append(reinterpret_cast<const char*>(evidence_.data()), evidence_.size() * sizeof(float));
  std::string file(kStateMagic, sizeof(kStateMagic));
  put(file, kStateVersion);
  put(file, static_cast<std::uint64_t>(payload.size()));
  put(file, fnv1a64(payload.data(), payload.size()));
  file += payload;
  // Write beside and rename, so a failed save never destroys the previous state.
  const auto tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out.write(file.data(), static_cast<std::streamsize>(file.size()));
    if (!out) throw Failure(located(tmp, 0, "cannot write map state"));
  }
  std::filesystem::rename(tmp, path);
}

OccupancyGridMapper OccupancyGridMapper::load_state(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw_input_error(path, 0, "cannot open map state");
  const std::string buf((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (buf.size() < sizeof(kStateMagic) || std::memcmp(buf.data(), kStateMagic, sizeof(kStateMagic)) != 0)
    throw_input_error(path, 0, "not a builtscene occupancy map state (bad magic)");
  std::size_t pos = sizeof(kStateMagic);
  const auto version = take<std::uint32_t>(buf, pos, path);
  if (version != kStateVersion)
    throw_input_error(path, 0, "unsupported map state version " + std::to_string(version));
  const auto size = take<std::uint64_t>(buf, pos, path);
  const auto sum = take<std::uint64_t>(buf, pos, path);
  if (buf.size() - pos != size) throw_input_error(path, 0, "map state is truncated or has trailing bytes");
  if (fnv1a64(buf.data() + pos, size) != sum) throw_input_error(path, 0, "map state checksum mismatch (corrupt file)");
  OccupancyMapperOptions o;
  const auto model = take<std::uint32_t>(buf, pos, path);
  if (model > 1) throw_input_error(path, 0, "unknown mapping model");
  o.model = static_cast<OccupancyMapperOptions::Model>(model);
  double v[9];
  for (double& x : v) x = take<double>(buf, pos, path);
  o.resolution = v[0];
  o.l_free = v[1];
  o.l_occ = v[2];
  o.p_free = v[3];
  o.p_occ = v[4];
  o.p_clamp = v[5];
  o.grow_margin = v[6];
  OccupancyGridMapper m(o);
  m.origin_ = {v[7], v[8]};
  m.width_ = take<std::int32_t>(buf, pos, path);
  m.height_ = take<std::int32_t>(buf, pos, path);
  m.scans_ = take<std::uint64_t>(buf, pos, path);
  if (m.width_ < 0 || m.height_ < 0) throw_input_error(path, 0, "negative grid size");
  const std::size_t cells = static_cast<std::size_t>(m.width_) * static_cast<std::size_t>(m.height_);
  if (buf.size() - pos != cells * sizeof(float)) throw_input_error(path, 0, "grid size does not match the data");
  m.evidence_.resize(cells);
  std::memcpy(m.evidence_.data(), buf.data() + pos, cells * sizeof(float));
  m.stamp_.assign(cells, 0);
  m.hit_.assign(cells, 0);
  return m;
}

}  // namespace builtscene
