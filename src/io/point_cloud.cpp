#include "io/point_cloud.hpp"

#include <cmath>
#include <algorithm>
#include <cstring>
#include <fstream>
#include <sstream>
#include <unordered_map>

#include "core/errors.hpp"

namespace builtscene {

void write_ply(const std::filesystem::path& path, const PointCloud& cloud) {
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  const auto tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\ncomment builtscene\nelement vertex " << cloud.size()
        << "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
           "property uchar blue\nend_header\n";
    std::vector<char> buf(cloud.size() * 15);
    char* p = buf.data();
    for (const auto& pt : cloud) {
      std::memcpy(p, pt.position.data(), 12);
      std::memcpy(p + 12, pt.rgb.data(), 3);
      p += 15;
    }
    out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
    if (!out) throw Failure(located(tmp, 0, "cannot write point cloud"));
  }
  // Replace atomically: an existing cloud is never left half-written.
  std::filesystem::rename(tmp, path);
}

PointCloud read_ply(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw_input_error(path, 0, "cannot open point cloud");
  std::string line;
  std::getline(in, line);
  if (line != "ply" && line != "ply\r") throw_input_error(path, 1, "not a PLY file");
  std::string format;
  std::size_t count = 0;
  struct Prop {
    std::string type, name;
  };
  std::vector<Prop> props;
  bool in_vertex = false;
  std::size_t line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ss(line);
    std::string word;
    ss >> word;
    if (word == "format") ss >> format;
    else if (word == "element") {
      std::string name;
      ss >> name >> count;
      in_vertex = name == "vertex";
      if (!in_vertex && !props.empty()) break;
    } else if (word == "property" && in_vertex) {
      Prop p;
      ss >> p.type >> p.name;
      if (p.type == "list") throw_input_error(path, line_no, "list properties on vertices are not supported");
      props.push_back(p);
    } else if (word == "end_header") break;
  }
  auto size_of = [&](const std::string& t) -> std::size_t {
    if (t == "float" || t == "float32" || t == "int" || t == "uint" || t == "int32" || t == "uint32") return 4;
    if (t == "double" || t == "float64") return 8;
    if (t == "uchar" || t == "uint8" || t == "char" || t == "int8") return 1;
    if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
    throw_input_error(path, 0, "unsupported property type '" + t + "'");
  };
  int ix = -1, iy = -1, iz = -1, ir = -1, ig = -1, ib = -1;
  for (std::size_t i = 0; i < props.size(); ++i) {
    const auto& n = props[i].name;
    const int k = static_cast<int>(i);
    if (n == "x") ix = k;
    else if (n == "y") iy = k;
    else if (n == "z") iz = k;
    else if (n == "red" || n == "r") ir = k;
    else if (n == "green" || n == "g") ig = k;
    else if (n == "blue" || n == "b") ib = k;
  }
  if (ix < 0 || iy < 0 || iz < 0) throw_input_error(path, 0, "vertex element lacks x, y or z");
  PointCloud cloud(count);
  std::vector<double> v(props.size());
  if (format == "ascii") {
    for (std::size_t n = 0; n < count; ++n) {
      for (auto& x : v)
        if (!(in >> x)) throw_input_error(path, 0, "point cloud is truncated");
      cloud[n].position = Eigen::Vector3f(static_cast<float>(v[static_cast<std::size_t>(ix)]), static_cast<float>(v[static_cast<std::size_t>(iy)]), static_cast<float>(v[static_cast<std::size_t>(iz)]));
      if (ir >= 0 && ig >= 0 && ib >= 0)
        cloud[n].rgb = {static_cast<std::uint8_t>(v[static_cast<std::size_t>(ir)]), static_cast<std::uint8_t>(v[static_cast<std::size_t>(ig)]), static_cast<std::uint8_t>(v[static_cast<std::size_t>(ib)])};
    }
    return cloud;
  }
  if (format != "binary_little_endian") throw_input_error(path, 0, "unsupported PLY format '" + format + "'");
  std::size_t stride = 0;
  std::vector<std::size_t> offset;
  for (const auto& p : props) {
    offset.push_back(stride);
    stride += size_of(p.type);
  }
  std::vector<char> rec(stride);
  auto value = [&](int k) -> double {
    const auto& t = props[static_cast<std::size_t>(k)].type;
    const char* p = rec.data() + offset[static_cast<std::size_t>(k)];
    if (t == "float" || t == "float32") { float f; std::memcpy(&f, p, 4); return f; }
    if (t == "double" || t == "float64") { double d; std::memcpy(&d, p, 8); return d; }
    if (t == "uchar" || t == "uint8") return static_cast<unsigned char>(*p);
    throw_input_error(path, 0, "unsupported type '" + t + "' for " + props[static_cast<std::size_t>(k)].name);
  };
  for (std::size_t n = 0; n < count; ++n) {
    if (!in.read(rec.data(), static_cast<std::streamsize>(stride))) throw_input_error(path, 0, "point cloud is truncated");
    cloud[n].position = Eigen::Vector3f(static_cast<float>(value(ix)), static_cast<float>(value(iy)), static_cast<float>(value(iz)));
    if (ir >= 0 && ig >= 0 && ib >= 0)
      cloud[n].rgb = {static_cast<std::uint8_t>(value(ir)), static_cast<std::uint8_t>(value(ig)), static_cast<std::uint8_t>(value(ib))};
  }
  return cloud;
}

PointCloud voxel_downsample(const PointCloud& cloud, double voxel) {
  if (!(voxel > 0)) return cloud;
  struct Acc {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Vector3d rgb = Eigen::Vector3d::Zero();
    std::size_t n = 0, first = 0;
  };
  auto key = [voxel](const Eigen::Vector3f& p) {
    const auto q = [voxel](float v) { return static_cast<std::int64_t>(std::floor(v / voxel)) & 0x1FFFFF; };
    return (q(p.x()) << 42) | (q(p.y()) << 21) | q(p.z());
  };
  std::unordered_map<std::int64_t, Acc> voxels;
  voxels.reserve(cloud.size() / 4 + 1);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto& pt = cloud[i];
    auto [it, inserted] = voxels.try_emplace(key(pt.position));
    Acc& a = it->second;
    if (inserted) a.first = i;
    a.sum += pt.position.cast<double>();
    a.rgb += Eigen::Vector3d(pt.rgb[0], pt.rgb[1], pt.rgb[2]);
    ++a.n;
  }
  // Output ordered by each voxel's first point: deterministic regardless of hashing.
  std::vector<const Acc*> order;
  order.reserve(voxels.size());
  for (const auto& [k, a] : voxels) order.push_back(&a);
  std::sort(order.begin(), order.end(), [](const Acc* a, const Acc* b) { return a->first < b->first; });
  PointCloud out;
  out.reserve(order.size());
  for (const Acc* a : order) {
    const double n = static_cast<double>(a->n);
    const Eigen::Vector3d c = a->rgb / n;
    out.push_back({(a->sum / n).cast<float>(),
                   {static_cast<std::uint8_t>(std::lround(c.x())), static_cast<std::uint8_t>(std::lround(c.y())),
                    static_cast<std::uint8_t>(std::lround(c.z()))}});
  }
  return out;
}

}  // namespace builtscene
