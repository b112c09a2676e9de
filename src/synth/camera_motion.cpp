#include "synth/camera_motion.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "synth/truth_map.hpp"

namespace builtscene::synth {
namespace {

using V2 = Eigen::Vector2d;
using V3 = Eigen::Vector3d;

// splitmix64: a tiny generator whose output is the same on every platform and library.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : s_(seed * 0x9E3779B97F4A7C15ull + 0x1234567ull) {}
  std::uint64_t next() {
    std::uint64_t z = (s_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform(double a = 0, double b = 1) { return a + (b - a) * static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }

 private:
  std::uint64_t s_;
};

// Smooth pseudo-random signal: a few sinusoids with random frequencies in [f0, f1] and phases.
struct Wobble {
  double a[4], f[4], p[4];
  Wobble(Rng& rng, double amplitude, double f0, double f1) {
    for (int i = 0; i < 4; ++i) {
      a[i] = amplitude / 2.0 * rng.uniform(0.5, 1.0);
      f[i] = rng.uniform(f0, f1);
      p[i] = rng.uniform(0, 2 * std::numbers::pi);
    }
  }
  double operator()(double t) const {
    double v = 0;
    for (int i = 0; i < 4; ++i) v += a[i] * std::sin(2 * std::numbers::pi * f[i] * t + p[i]);
    return v;
  }
};

struct PathSample {
  V2 p;
  double heading;
  double curvature;
};

// The closed loop with its corners replaced by circular arcs, sampled every `ds` metres.
std::vector<PathSample> rounded_loop(const std::vector<V2>& corners, double radius, double ds) {
  const std::size_t n = corners.size();
  if (n < 3) throw std::invalid_argument("robot loop needs at least 3 corners");
  std::vector<double> tl(n), r(n);
  for (std::size_t i = 0; i < n; ++i) {
    const V2 a = corners[(i + n - 1) % n], c = corners[i], d = corners[(i + 1) % n];
    const V2 d1 = (c - a).normalized(), d2 = (d - c).normalized();
    const double turn = std::acos(std::clamp(d1.dot(d2), -1.0, 1.0));
    const double maxtl = 0.45 * std::min((c - a).norm(), (d - c).norm());
    double ri = radius;
    if (turn < 1e-6) {
      tl[i] = 0;
      r[i] = 0;
      continue;
    }
    double t = ri * std::tan(turn / 2);
    if (t > maxtl) {
      t = maxtl;
      ri = t / std::tan(turn / 2);
    }
    tl[i] = t;
    r[i] = ri;
  }
  std::vector<PathSample> out;
  for (std::size_t i = 0; i < n; ++i) {
    const V2 a = corners[i], c = corners[(i + 1) % n];
    const V2 dir = (c - a).normalized();
    const double h = std::atan2(dir.y(), dir.x());
    const V2 s0 = a + dir * tl[i], s1 = c - dir * tl[(i + 1) % n];
    const double len = (s1 - s0).norm();
    for (double s = 0; s < len; s += ds) out.push_back({s0 + dir * s, h, 0.0});
    // Arc at corner i+1.
    const std::size_t k = (i + 1) % n;
    if (r[k] <= 0) continue;
    const V2 dnext = (corners[(k + 1) % n] - corners[k]).normalized();
    const double cross = dir.x() * dnext.y() - dir.y() * dnext.x();
    const double sign = cross > 0 ? 1.0 : -1.0;  // left turn positive
    const V2 normal = V2(-dir.y(), dir.x()) * sign;
    const V2 centre = s1 + normal * r[k];
    const double turn = std::acos(std::clamp(dir.dot(dnext), -1.0, 1.0));
    const double arc = turn * r[k];
    for (double s = 0; s < arc; s += ds) {
      const double ang = s / r[k] * sign;
      const V2 radial = s1 - centre;
      const V2 p = centre + V2(std::cos(ang) * radial.x() - std::sin(ang) * radial.y(), std::sin(ang) * radial.x() + std::cos(ang) * radial.y());
      out.push_back({p, h + ang, sign / r[k]});
    }
  }
  return out;
}

SE3 make_pose(const V3& pos, const V3& forward, double roll) { return SE3(look_rotation(forward, roll), pos); }

MotionResult robot_motion(const Scene& scene, const MotionOptions& opt) {
  MotionResult res;
  const double ds = 0.01;
  const auto path = rounded_loop(scene.robot_loop, 0.8, ds);
  const std::size_t n = path.size();
  const double L = static_cast<double>(n) * ds;
  res.loop_length_m = L;
  // Speed limit per sample: cruise on straights, bounded yaw rate in turns, then limited
  // acceleration (two passes each way around the cyclic loop).
  const double omega_max = 0.5, acc = 0.35;
  std::vector<double> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = std::min(opt.robot_speed, path[i].curvature != 0 ? omega_max / std::abs(path[i].curvature) : 1e9);
  for (int pass = 0; pass < 2; ++pass) {
    for (std::size_t k = 1; k <= n; ++k) {
      const std::size_t i = k % n, j = k - 1;
      v[i] = std::min(v[i], std::sqrt(v[j] * v[j] + 2 * acc * ds));
    }
    for (std::size_t k = n; k-- > 1;) {
      const std::size_t i = k - 1, j = k % n;
      v[i] = std::min(v[i], std::sqrt(v[j] * v[j] + 2 * acc * ds));
    }
  }
  double loop_time = 0;
  for (std::size_t i = 0; i < n; ++i) loop_time += ds / v[i];
  const int frames = opt.frames > 0 ? opt.frames : static_cast<int>(std::ceil(opt.loops * loop_time * opt.fps)) + 1;
  Rng rng(opt.seed ^ 0x5151ull);
  const Wobble pitch_w(rng, 0.4 * std::numbers::pi / 180, 1.0, 4.0), roll_w(rng, 0.3 * std::numbers::pi / 180, 1.0, 4.0), yaw_w(rng, 0.3 * std::numbers::pi / 180, 0.3, 2.0),
      z_w(rng, 0.004, 1.5, 5.0), lat_w(rng, 0.02, 0.05, 0.2);
  const double dt = 1.0 / opt.fps;
  double s = 0;
  for (int f = 0; f < frames; ++f) {
    const double t = f * dt;
    const double sl = std::fmod(s, L);
    const double idx = sl / ds;
    const std::size_t i0 = static_cast<std::size_t>(idx) % n, i1 = (i0 + 1) % n;
    const double a = idx - std::floor(idx);
    const V2 p = path[i0].p * (1 - a) + path[i1].p * a;
    double dh = path[i1].heading - path[i0].heading;
    dh = std::remainder(dh, 2 * std::numbers::pi);
    const double heading = path[i0].heading + a * dh + yaw_w(t);
    const V2 dir(std::cos(path[i0].heading), std::sin(path[i0].heading));
    const V2 pl = p + V2(-dir.y(), dir.x()) * lat_w(t);  // the driver does not hold the line exactly
    const double pitch = opt.robot_pitch_deg * std::numbers::pi / 180 + pitch_w(t);
    const V3 fwd(std::cos(heading) * std::cos(pitch), std::sin(heading) * std::cos(pitch), -std::sin(pitch));
    res.poses.push_back(make_pose(V3(pl.x(), pl.y(), opt.robot_camera_height + z_w(t)), fwd, roll_w(t)));
    // Advance along the loop (midpoint rule).
    const double v0 = v[i0];
    const double smid = std::fmod(sl + v0 * dt / 2, L);
    s += v[static_cast<std::size_t>(smid / ds) % n] * dt;
  }
  return res;
}

// Cubic Hermite through (t_i, y_i) with finite-difference tangents (Catmull-Rom, non-uniform).
template <typename T>
T hermite(const std::vector<double>& ts, const std::vector<T>& ys, double t) {
  const std::size_t n = ts.size();
  std::size_t i = 0;
  while (i + 2 < n && ts[i + 1] < t) ++i;
  const double t0 = ts[i], t1 = ts[i + 1];
  const double h = t1 - t0;
  const double u = std::clamp((t - t0) / h, 0.0, 1.0);
  auto tangent = [&](std::size_t k) -> T {
    if (k == 0) return (ys[1] - ys[0]) / (ts[1] - ts[0]);
    if (k == n - 1) return (ys[n - 1] - ys[n - 2]) / (ts[n - 1] - ts[n - 2]);
    return (ys[k + 1] - ys[k - 1]) / (ts[k + 1] - ts[k - 1]);
  };
  // Zero tangents at waypoints where the camera stops turning keep the look steady there;
  // we use a damped Catmull-Rom tangent for a calmer hand.
  const T m0 = tangent(i) * 0.7, m1 = tangent(i + 1) * 0.7;
  const double u2 = u * u, u3 = u2 * u;
  return ys[i] * (2 * u3 - 3 * u2 + 1) + m0 * (h * (u3 - 2 * u2 + u)) + ys[i + 1] * (-2 * u3 + 3 * u2) + m1 * (h * (u3 - u2));
}

MotionResult handheld_motion(const Scene& scene, const MotionOptions& opt) {
  MotionResult res;
  const int frames = opt.frames > 0 ? opt.frames : 300;
  const double duration = frames / opt.fps;
  // Where a walking person fits: the truth map of the band their body occupies.
  const OccupancyTruth body = compute_truth_map(scene, 0.05, 1.9, 0.05);
  const cv::Mat clear = clearance_map(body);
  auto clearance = [&](const V2& p) -> double {
    int c, r;
    if (!body.cell_of(p.x(), p.y(), c, r)) return 0.0;
    return clear.at<float>(r, c);
  };
  auto segment_clear = [&](const V2& a, const V2& b, double need) {
    const int steps = std::max(2, static_cast<int>((b - a).norm() / 0.05));
    for (int k = 0; k <= steps; ++k)
      if (clearance(a + (b - a) * (static_cast<double>(k) / steps)) < need) return false;
    return true;
  };
  const auto surfaces = scene_surfaces(scene);
  Rng rng(opt.seed ^ 0xA11CEull);

  // Start: a random well-clear spot.
  V2 pos;
  for (int tries = 0;; ++tries) {
    const auto& f = scene.floor[static_cast<std::size_t>(rng.next() % scene.floor.size())];
    pos = V2(rng.uniform(f.x0, f.x1), rng.uniform(f.y0, f.y1));
    if (clearance(pos) >= 0.6 || (tries > 2000 && clearance(pos) >= 0.35)) break;
    if (tries > 5000) throw std::runtime_error("scene " + scene.name + ": no free start position");
  }
  std::vector<double> ts;
  std::vector<V3> ps;
  std::vector<V2> angles;  // yaw (unwrapped), pitch
  double t = 0;
  double yaw_prev = rng.uniform(-std::numbers::pi, std::numbers::pi);
  auto view_of = [&](const V3& eye, bool want_far_turn, double& yaw, double& pitch) {
    // Visible look targets at a comfortable distance; a fast turn prefers one far around.
    std::vector<std::pair<double, V3>> cand;
    for (const auto& tg : scene.look_targets) {
      const V3 d = tg - eye;
      const double dist = d.norm();
      if (dist < 1.0 || dist > 5.5) continue;
      const auto hit = raycast(surfaces, eye, d / dist, 1e-3);
      if (hit && *hit < dist - 0.15) continue;
      const double y = std::atan2(d.y(), d.x());
      const double turn = std::abs(std::remainder(y - yaw_prev, 2 * std::numbers::pi));
      if (want_far_turn ? turn < 1.6 : turn > 1.7) continue;
      cand.emplace_back(turn, tg);
    }
    if (!cand.empty()) {
      const V3 tg = cand[static_cast<std::size_t>(rng.next() % cand.size())].second;
      const V3 d = tg - eye;
      yaw = std::atan2(d.y(), d.x());
      pitch = std::atan2(d.z(), std::hypot(d.x(), d.y()));
      return true;
    }
    // Nothing listed in view: look where there is the most room, slightly down.
    double best = -1;
    for (int k = 0; k < 16; ++k) {
      const double y = yaw_prev + (want_far_turn ? std::numbers::pi : 0) + (k - 8) * std::numbers::pi / 16 * (want_far_turn ? 0.8 : 0.5);
      const V3 dir(std::cos(y) * std::cos(0.25), std::sin(y) * std::cos(0.25), -std::sin(0.25));
      const auto hit = raycast(surfaces, eye, dir, 1e-3);
      const double d = hit ? std::min(*hit, 6.0) : 6.0;
      if (d > best) {
        best = d;
        yaw = y;
      }
    }
    pitch = -0.25;
    return false;
  };
  double height = rng.uniform(1.2, 1.6);
  double last_fast = 0;
  while (true) {
    const V3 eye(pos.x(), pos.y(), height);
    // Fast turns now and then, and at least every 8 s.
    const bool fast = !ts.empty() && (rng.uniform() < 0.12 || t - last_fast > 8.0);
    if (fast) last_fast = t;
    double yaw = 0, pitch = 0;
    view_of(eye, fast, yaw, pitch);
    yaw = yaw_prev + std::remainder(yaw - yaw_prev, 2 * std::numbers::pi);  // unwrap
    pitch = std::clamp(pitch, -0.9, 0.45);
    if (!ts.empty()) {
      const double dist = (eye - ps.back()).norm();
      const double turn = std::abs(yaw - angles.back().x()) + std::abs(pitch - angles.back().y());
      const double dtseg = fast ? std::max({dist / 0.8, turn / (200.0 * std::numbers::pi / 180), 0.35})
                                : std::max({dist / 0.4, turn / (45.0 * std::numbers::pi / 180), 1.0});
      if (fast) ++res.fast_turns;
      t += dtseg;
    }
    ts.push_back(t);
    ps.push_back(eye);
    angles.push_back(V2(yaw, pitch));
    yaw_prev = yaw;
    if (t > duration + 1.0 && ts.size() >= 3) break;
    // Next waypoint: a step roughly ahead, with room around it and along the way.
    bool found = false;
    for (int tries = 0; tries < 400 && !found; ++tries) {
      const double need = tries < 200 ? 0.45 : 0.3;
      const double ang = yaw + rng.uniform(-1.8, 1.8) * (tries < 100 ? 0.6 : 1.7);
      const double step = rng.uniform(0.4, 1.5);
      const V2 cand = pos + V2(std::cos(ang), std::sin(ang)) * step;
      // Walk where the camera, still looking roughly the same way, has room in front of it.
      const V3 ahead(std::cos(yaw), std::sin(yaw), 0.0);
      const auto room = tries < 300 ? raycast(surfaces, V3(cand.x(), cand.y(), height), ahead, 1e-3) : std::optional<double>(9.0);
      if (room && *room < 1.0) continue;
      if (clearance(cand) >= need && segment_clear(pos, cand, need - 0.05)) {
        pos = cand;
        found = true;
      }
    }
    height = std::clamp(height + rng.uniform(-0.15, 0.15), 1.1, 1.7);
  }
  Rng wr(opt.seed ^ 0xB0Bull);
  const Wobble yaw_w(wr, 0.5 * std::numbers::pi / 180, 0.8, 3.0), pitch_w(wr, 0.5 * std::numbers::pi / 180, 0.8, 3.0), roll_w(wr, 4.0 * std::numbers::pi / 180, 0.05, 0.3),
      trem(wr, 0.15 * std::numbers::pi / 180, 4.0, 8.0), bob(wr, 0.012, 1.6, 2.0), sway(wr, 0.006, 0.8, 1.1);
  for (int f = 0; f < frames; ++f) {
    const double tf = f / opt.fps;
    V3 p = hermite(ts, ps, tf);
    const V2 a = hermite(ts, angles, tf);
    p.z() += bob(tf);
    p.x() += sway(tf);
    p.y() += sway(tf + 3.7);
    const double yaw = a.x() + yaw_w(tf) + trem(tf);
    const double pitch = std::clamp(a.y() + pitch_w(tf) + trem(tf + 1.3), -1.2, 0.8);
    const V3 fwd(std::cos(yaw) * std::cos(pitch), std::sin(yaw) * std::cos(pitch), std::sin(pitch));
    res.poses.push_back(make_pose(p, fwd, roll_w(tf)));
  }
  return res;
}

}  // namespace

Eigen::Matrix3d look_rotation(const Eigen::Vector3d& forward, double roll) {
  const V3 z = forward.normalized();
  V3 x = z.cross(V3::UnitZ());
  if (x.norm() < 1e-6) x = V3::UnitX();
  x.normalize();
  const V3 y = z.cross(x);
  Eigen::Matrix3d R;
  R.col(0) = x;
  R.col(1) = y;
  R.col(2) = z;
  return R * Eigen::AngleAxisd(roll, V3::UnitZ()).toRotationMatrix();
}

MotionResult generate_motion(const Scene& scene, const MotionOptions& options) {
  if (options.kind == MotionKind::Robot) return robot_motion(scene, options);
  return handheld_motion(scene, options);
}

}  // namespace builtscene::synth
