#include "synth/renderer.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <thread>

#include <opencv2/imgproc.hpp>

#include "core/errors.hpp"

namespace builtscene::synth {

struct Renderer::MipTexture {
  struct Level {
    int w, h;
    std::vector<float> bgr;  // w*h*3
    bool pow2 = false;       // wrap with a mask instead of a modulo
  };
  std::vector<Level> levels;

  explicit MipTexture(const cv::Mat& img8) {
    cv::Mat cur;
    img8.convertTo(cur, CV_32FC3);
    while (true) {
      Level l{cur.cols, cur.rows, {}, (cur.cols & (cur.cols - 1)) == 0 && (cur.rows & (cur.rows - 1)) == 0};
      l.bgr.resize(static_cast<std::size_t>(cur.cols) * cur.rows * 3);
      for (int y = 0; y < cur.rows; ++y) std::memcpy(&l.bgr[static_cast<std::size_t>(y) * cur.cols * 3], cur.ptr<float>(y), sizeof(float) * 3 * cur.cols);
      levels.push_back(std::move(l));
      if (cur.cols <= 1 && cur.rows <= 1) break;
      cv::Mat next;
      cv::resize(cur, next, cv::Size(std::max(1, cur.cols / 2), std::max(1, cur.rows / 2)), 0, 0, cv::INTER_AREA);
      cur = next;
    }
  }

  // Bilinear sample at normalized (u, v), wrapping (repeat) or clamping.
  inline void bilinear(int lev, float u, float v, bool wrap, float* out) const {
    const Level& L = levels[static_cast<std::size_t>(lev)];
    float x = u * L.w - 0.5f, y = v * L.h - 0.5f;
    float fx0 = std::floor(x), fy0 = std::floor(y);
    const float ax = x - fx0, ay = y - fy0;
    int x0 = static_cast<int>(fx0), y0 = static_cast<int>(fy0);
    int x1 = x0 + 1, y1 = y0 + 1;
    if (wrap && L.pow2) {
      x0 &= L.w - 1;
      x1 &= L.w - 1;
      y0 &= L.h - 1;
      y1 &= L.h - 1;
    } else if (wrap) {
      x0 = ((x0 % L.w) + L.w) % L.w;
      x1 = ((x1 % L.w) + L.w) % L.w;
      y0 = ((y0 % L.h) + L.h) % L.h;
      y1 = ((y1 % L.h) + L.h) % L.h;
    } else {
      x0 = std::clamp(x0, 0, L.w - 1);
      x1 = std::clamp(x1, 0, L.w - 1);
      y0 = std::clamp(y0, 0, L.h - 1);
      y1 = std::clamp(y1, 0, L.h - 1);
    }
    const float* p00 = &L.bgr[(static_cast<std::size_t>(y0) * L.w + x0) * 3];
    const float* p01 = &L.bgr[(static_cast<std::size_t>(y0) * L.w + x1) * 3];
    const float* p10 = &L.bgr[(static_cast<std::size_t>(y1) * L.w + x0) * 3];
    const float* p11 = &L.bgr[(static_cast<std::size_t>(y1) * L.w + x1) * 3];
    for (int c = 0; c < 3; ++c) {
      const float top = p00[c] + (p01[c] - p00[c]) * ax;
      const float bot = p10[c] + (p11[c] - p10[c]) * ax;
      out[c] = top + (bot - top) * ay;
    }
  }

  inline void trilinear(float u, float v, float lod, bool wrap, float* out) const {
    const int maxl = static_cast<int>(levels.size()) - 1;
    if (lod <= 0.f) {
      bilinear(0, u, v, wrap, out);
      return;
    }
    if (lod >= static_cast<float>(maxl)) {
      bilinear(maxl, u, v, wrap, out);
      return;
    }
    const int l0 = static_cast<int>(lod);
    const float f = lod - static_cast<float>(l0);
    float a[3], b[3];
    bilinear(l0, u, v, wrap, a);
    bilinear(l0 + 1, u, v, wrap, b);
    for (int c = 0; c < 3; ++c) out[c] = a[c] + (b[c] - a[c]) * f;
  }
};

// Irradiance on a grid over one surface (s along u, t along v), sampled bilinearly.
struct Renderer::LightMap {
  int w = 2, h = 2;
  std::vector<float> e;
  inline float sample(float s01, float t01) const {
    const float x = std::clamp(s01, 0.f, 1.f) * static_cast<float>(w - 1);
    const float y = std::clamp(t01, 0.f, 1.f) * static_cast<float>(h - 1);
    const int x0 = std::min(static_cast<int>(x), w - 2), y0 = std::min(static_cast<int>(y), h - 2);
    const float ax = x - static_cast<float>(x0), ay = y - static_cast<float>(y0);
    const float* r0 = &e[static_cast<std::size_t>(y0) * w + x0];
    const float* r1 = r0 + w;
    const float top = r0[0] + (r0[1] - r0[0]) * ax;
    const float bot = r1[0] + (r1[1] - r1[0]) * ax;
    return top + (bot - top) * ay;
  }
};

namespace {

// log2 of a positive float, accurate to ~0.01: exponent plus a quadratic in the mantissa.
inline float fast_log2(float x) {
  std::uint32_t bits;
  std::memcpy(&bits, &x, 4);
  const float e = static_cast<float>(static_cast<int>((bits >> 23) & 255) - 127);
  bits = (bits & 0x007FFFFFu) | 0x3F800000u;
  float m;
  std::memcpy(&m, &bits, 4);
  return e + (-0.34484843f * m + 2.02466578f) * m - 0.67487759f;
}

// A surface reduced to what a shadow ray needs, precomputed once.
struct Occluder {
  Eigen::Vector3d o, n, uu, vv;  // origin, normal (unnormalized), u / |u|^2, v / |v|^2
  double c;                      // n . o
};

// Does the segment q + t dir, t in (0, len), cross any surface?
bool occluded(const std::vector<Occluder>& occ, const Eigen::Vector3d& q, const Eigen::Vector3d& dir, double len) {
  for (const Occluder& s : occ) {
    const double den = s.n.dot(dir);
    if (std::abs(den) < 1e-15) continue;
    const double t = (s.c - s.n.dot(q)) / den;
    if (t <= 1e-4 || t >= len) continue;
    const Eigen::Vector3d d = q + dir * t - s.o;
    const double a = d.dot(s.uu), b = d.dot(s.vv);
    if (a >= 0 && a <= 1 && b >= 0 && b <= 1) return true;
  }
  return false;
}

// Lights farther than this add less than ~0.03 to a surface's irradiance: ignored.
constexpr double kLightRange = 9.0;

std::unique_ptr<Renderer::LightMap> compute_lightmap(const Surface& sf, const std::vector<Occluder>& occ, const Scene& scene) {
  auto lm = std::make_unique<Renderer::LightMap>();
  const double lu = sf.u.norm(), lv = sf.v.norm();
  const double cell = std::max({0.15, lu / 160.0, lv / 160.0});
  lm->w = std::max(2, static_cast<int>(std::ceil(lu / cell)) + 1);
  lm->h = std::max(2, static_cast<int>(std::ceil(lv / cell)) + 1);
  lm->e.assign(static_cast<std::size_t>(lm->w) * lm->h, static_cast<float>(scene.ambient));
  const Eigen::Vector3d n = sf.v.cross(sf.u).normalized();  // the visible side
  // Lights that can reach some part of this surface (in front of it, within range).
  std::vector<const Light*> lights;
  const Eigen::Vector3d centre = sf.origin + (sf.u + sf.v) / 2;
  const double radius = (sf.u + sf.v).norm() / 2;
  for (const Light& L : scene.lights)
    if (n.dot(L.position - sf.origin) > 0 && (L.position - centre).norm() < kLightRange + radius) lights.push_back(&L);
  for (int j = 0; j < lm->h; ++j)
    for (int i = 0; i < lm->w; ++i) {
      const Eigen::Vector3d p = sf.origin + sf.u * (static_cast<double>(i) / (lm->w - 1)) + sf.v * (static_cast<double>(j) / (lm->h - 1));
      const Eigen::Vector3d q = p + n * 0.01;
      double e = scene.ambient;
      for (const Light* L : lights) {
        const Eigen::Vector3d d = L->position - q;
        const double dist2 = d.squaredNorm();
        if (dist2 > kLightRange * kLightRange) continue;
        const double dist = std::sqrt(dist2);
        const double cosang = n.dot(d) / dist;
        if (cosang <= 0) continue;
        if (occluded(occ, q, d / dist, dist - 0.02)) continue;  // in shadow
        // Inverse square with a soft core so that surfaces next to a lamp do not blow out.
        e += L->intensity * cosang / (dist2 + 0.5);
      }
      lm->e[static_cast<std::size_t>(j) * lm->w + i] = static_cast<float>(e);
    }
  return lm;
}

}  // namespace

Renderer::Renderer(const Scene& scene, const PinholeCamera& camera) : camera_(camera), surfaces_(scene_surfaces(scene)), materials_(scene.materials) {
  for (const auto& t : scene.textures) textures_.push_back(std::make_unique<MipTexture>(t.second));
  for (const auto& m : materials_) {
    const int ti = scene.texture_index(m.texture);
    if (ti < 0) throw Failure("scene " + scene.name + ": material uses unknown texture " + m.texture);
    material_texture_.push_back(ti);
  }
  for (const auto& s : surfaces_)
    if (s.material < 0 || s.material >= static_cast<int>(materials_.size())) throw Failure("scene " + scene.name + ": surface with a bad material");
  lightmaps_.resize(surfaces_.size());
  std::vector<Occluder> occ;
  for (const auto& sf : surfaces_) {
    const Eigen::Vector3d nn = sf.u.cross(sf.v);
    occ.push_back({sf.origin, nn, sf.u / sf.u.squaredNorm(), sf.v / sf.v.squaredNorm(), nn.dot(sf.origin)});
  }
  // Light maps are independent per surface: compute them in two interleaved halves.
  auto work = [&](std::size_t first) {
    for (std::size_t i = first; i < surfaces_.size(); i += 2) lightmaps_[i] = compute_lightmap(surfaces_[i], occ, scene);
  };
  std::thread t(work, 1);
  work(0);
  t.join();
}

Renderer::~Renderer() = default;

void Renderer::render(const SE3& T_wc, RenderOutput& out, int threads) const {
  const int W = camera_.width, H = camera_.height;
  out.bgr.create(H, W, CV_32FC3);
  out.depth.create(H, W, CV_32F);
  out.incidence.create(H, W, CV_32F);
  const SE3 T_cw = T_wc.inverse();
  threads = std::clamp(threads, 1, 8);
  if (threads == 1) {
    render_rows(T_cw, out, 0, H);
    return;
  }
  std::vector<std::thread> pool;
  for (int k = 1; k < threads; ++k) pool.emplace_back([&, k] { render_rows(T_cw, out, H * k / threads, H * (k + 1) / threads); });
  render_rows(T_cw, out, 0, H / threads);
  for (auto& t : pool) t.join();
}

void Renderer::render_rows(const SE3& T_cw, RenderOutput& out, int row_begin, int row_end) const {
  const int W = camera_.width;
  const float fx = static_cast<float>(camera_.fx), fy = static_cast<float>(camera_.fy);
  const float cx = static_cast<float>(camera_.cx), cy = static_cast<float>(camera_.cy);
  const float inf = std::numeric_limits<float>::infinity();
  for (int y = row_begin; y < row_end; ++y) {
    float* z = out.depth.ptr<float>(y);
    float* c = out.bgr.ptr<float>(y);
    float* inc = out.incidence.ptr<float>(y);
    std::fill(z, z + W, inf);
    std::fill(c, c + 3 * W, 0.f);
    std::fill(inc, inc + W, 0.f);
  }
  const Eigen::Matrix3d R = T_cw.rotation_matrix();
  const Eigen::Vector3d t = T_cw.translation();
  constexpr double znear = 0.02;

  // Front to back, so that the depth test rejects hidden pixels before they are shaded.
  // Ties in distance keep the scene order, so the result is the same for every thread count.
  const Eigen::Vector3d eye = -(R.transpose() * t);
  std::vector<std::pair<double, std::size_t>> order(surfaces_.size());
  for (std::size_t si = 0; si < surfaces_.size(); ++si) {
    const Surface& sf = surfaces_[si];
    const Eigen::Vector3d d = eye - sf.origin;
    const double a = std::clamp(d.dot(sf.u) / sf.u.squaredNorm(), 0.0, 1.0), b = std::clamp(d.dot(sf.v) / sf.v.squaredNorm(), 0.0, 1.0);
    order[si] = {(sf.origin + sf.u * a + sf.v * b - eye).squaredNorm(), si};
  }
  std::sort(order.begin(), order.end());

  for (const auto& [dist2, si] : order) {
    const Surface& sf = surfaces_[si];
    const Eigen::Vector3d o = R * sf.origin + t;
    const Eigen::Vector3d uc = R * sf.u, vc = R * sf.v;
    const double lu = uc.norm(), lv = vc.norm();
    const Eigen::Vector3d eu = uc / lu, ev = vc / lv;
    const Eigen::Vector3d n = vc.cross(uc).normalized();  // front normal, camera frame
    const double plane_c = n.dot(o);                        // n . p = plane_c on the surface
    if (plane_c >= -1e-9) continue;  // camera behind or in the plane: the front is not visible

    // Clip the rectangle at the near plane (Sutherland-Hodgman on one plane).
    const Eigen::Vector3d quad[4] = {o, o + uc, o + uc + vc, o + vc};
    Eigen::Vector2d poly[8];
    int np = 0;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d& a = quad[k];
      const Eigen::Vector3d& b = quad[(k + 1) % 4];
      const bool ina = a.z() >= znear, inb = b.z() >= znear;
      if (ina) poly[np++] = {fx * a.x() / a.z() + cx, fy * a.y() / a.z() + cy};
      if (ina != inb) {
        const double s = (znear - a.z()) / (b.z() - a.z());
        const Eigen::Vector3d p = a + (b - a) * s;
        poly[np++] = {fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy};
      }
    }
    if (np < 3) continue;
    double ymin = 1e30, ymax = -1e30, xmin = 1e30, xmax = -1e30;
    for (int k = 0; k < np; ++k) {
      ymin = std::min(ymin, poly[k].y());
      ymax = std::max(ymax, poly[k].y());
      xmin = std::min(xmin, poly[k].x());
      xmax = std::max(xmax, poly[k].x());
    }
    if (xmax < -1 || xmin > W) continue;
    const int y0 = std::max(row_begin, static_cast<int>(std::ceil(ymin - 1e-4)));
    const int y1 = std::min(row_end - 1, static_cast<int>(std::floor(ymax + 1e-4)));
    if (y0 > y1) continue;

    // Per-pixel linear forms in (x, y): den = n . ray, ns = eu . ray, nt = ev . ray,
    // with ray = ((x - cx) / fx, (y - cy) / fy, 1).
    auto lin = [&](const Eigen::Vector3d& a, float& ax, float& ay, float& a0) {
      ax = static_cast<float>(a.x() / fx);
      ay = static_cast<float>(a.y() / fy);
      a0 = static_cast<float>(a.z() - a.x() * cx / fx - a.y() * cy / fy);
    };
    float A, B, C, Su, Sv, S0, Tu, Tv, T0;
    lin(n, A, B, C);
    lin(eu, Su, Sv, S0);
    lin(ev, Tu, Tv, T0);
    const float pc = static_cast<float>(plane_c);
    const float so = static_cast<float>(eu.dot(o)), to = static_cast<float>(ev.dot(o));
    const Material& m = materials_[static_cast<std::size_t>(sf.material)];
    const MipTexture& tex = *textures_[static_cast<std::size_t>(material_texture_[static_cast<std::size_t>(sf.material)])];
    const LightMap& lm = *lightmaps_[si];
    const bool wrap = m.mapping == TextureMapping::Repeat;
    const int tw = tex.levels[0].w, th = tex.levels[0].h;
    // metres -> normalized texture coordinates
    const float ku = wrap ? static_cast<float>(1.0 / m.tile_m) : static_cast<float>(1.0 / lu);
    const float kv = wrap ? static_cast<float>(1.0 / (m.tile_m * th / tw)) : static_cast<float>(1.0 / lv);
    const float klu = static_cast<float>(1.0 / lu), klv = static_cast<float>(1.0 / lv);
    const float tint[3] = {m.tint.x(), m.tint.y(), m.tint.z()};

    for (int y = y0; y <= y1; ++y) {
      const double yc = y;
      double xl = 1e30, xr = -1e30;
      for (int k = 0; k < np; ++k) {
        const Eigen::Vector2d& a = poly[k];
        const Eigen::Vector2d& b = poly[(k + 1) % np];
        if ((yc < a.y() && yc < b.y()) || (yc > a.y() && yc > b.y())) continue;
        double xi;
        if (std::abs(b.y() - a.y()) < 1e-12) {
          xl = std::min({xl, a.x(), b.x()});
          xr = std::max({xr, a.x(), b.x()});
          continue;
        }
        xi = a.x() + (yc - a.y()) / (b.y() - a.y()) * (b.x() - a.x());
        xl = std::min(xl, xi);
        xr = std::max(xr, xi);
      }
      const int xa = std::max(0, static_cast<int>(std::ceil(xl - 1e-4)));
      const int xb = std::min(W - 1, static_cast<int>(std::floor(xr + 1e-4)));
      if (xa > xb) continue;
      float* zrow = out.depth.ptr<float>(y);
      float* crow = out.bgr.ptr<float>(y);
      float* irow = out.incidence.ptr<float>(y);
      const float fyv = static_cast<float>(y);
      const float ray_y = (fyv - cy) / fy;
      for (int x = xa; x <= xb; ++x) {
        const float fxv = static_cast<float>(x);
        const float den = A * fxv + B * fyv + C;
        if (den >= 0.f) continue;  // ray parallel or leaving the front
        const float inv = 1.f / den;
        const float zz = pc * inv;
        if (zz <= static_cast<float>(znear) || zz >= zrow[x]) continue;
        const float qs = (Su * fxv + Sv * fyv + S0) * inv;
        const float qt = (Tu * fxv + Tv * fyv + T0) * inv;
        const float s_m = pc * qs - so, t_m = pc * qt - to;
        // Texture footprint of the pixel: derivatives of the texel coordinates.
        const float dsx = zz * (Su - A * qs) * ku * static_cast<float>(tw), dtx = zz * (Tu - A * qt) * kv * static_cast<float>(th);
        const float dsy = zz * (Sv - B * qs) * ku * static_cast<float>(tw), dty = zz * (Tv - B * qt) * kv * static_cast<float>(th);
        const float rho2 = std::max(dsx * dsx + dtx * dtx, dsy * dsy + dty * dty);
        const float lod = rho2 > 1e-12f ? 0.5f * fast_log2(rho2) : 0.f;
        float texel[3];
        tex.trilinear(s_m * ku, t_m * kv, lod, wrap, texel);
        const float e = lm.sample(s_m * klu, t_m * klv);
        zrow[x] = zz;
        float* px = crow + 3 * x;
        px[0] = texel[0] * tint[0] * e;
        px[1] = texel[1] * tint[1] * e;
        px[2] = texel[2] * tint[2] * e;
        const float rx = (fxv - cx) / fx;
        irow[x] = -den / std::sqrt(rx * rx + ray_y * ray_y + 1.f);
      }
    }
  }
  for (int y = row_begin; y < row_end; ++y) {
    float* z = out.depth.ptr<float>(y);
    for (int x = 0; x < W; ++x)
      if (!std::isfinite(z[x])) z[x] = 0.f;
  }
}

}  // namespace builtscene::synth
