#include "synth/warehouse_scene.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <numbers>
#include <random>
#include <thread>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <zint.h>

#include "core/errors.hpp"

namespace builtscene::synth {
namespace fs = std::filesystem;

namespace {

constexpr int kLevelH = 440;
constexpr int kBayW = 2200;
constexpr int kBeamH = 64;
constexpr int kPostW = 60;
constexpr int kMarginX = 500;
constexpr int kMarginTop = 260;
constexpr int kFloor = 260;
constexpr double kNominalScale = 0.75;  // frame pixels per world pixel

// Uniform [0,1) from a 64-bit generator, the same on every platform.
double unit(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0); }
double uniform(std::mt19937_64& rng, double a, double b) { return a + (b - a) * unit(rng); }

// Gray raster of a symbol from libzint, `module` world pixels per module (a multiple of 0.5 x 2).
cv::Mat render_symbol(const std::string& text, int symbology, float module, float height_modules) {
  zint_symbol* s = ZBarcode_Create();
  if (!s) throw Failure("libzint: out of memory");
  s->symbology = symbology;
  s->scale = module / 2.0f;  // zint's raster draws 2 pixels per module at scale 1
  s->height = height_modules;
  s->whitespace_width = 10;
  s->show_hrt = 1;
  const int err = ZBarcode_Encode_and_Buffer(s, reinterpret_cast<const unsigned char*>(text.data()),
                                             static_cast<int>(text.size()), 0);
  if (err >= ZINT_ERROR) {
    const std::string msg = s->errtxt;
    ZBarcode_Delete(s);
    throw Failure("libzint cannot encode '" + text + "': " + msg);
  }
  cv::Mat rgb(s->bitmap_height, s->bitmap_width, CV_8UC3, s->bitmap);
  cv::Mat gray;
  cv::cvtColor(rgb, gray, cv::COLOR_RGB2GRAY);
  ZBarcode_Delete(s);
  return gray;
}

std::string ean13_with_check(const std::string& d12) {
  int sum = 0;
  for (int i = 0; i < 12; ++i) sum += (d12[static_cast<std::size_t>(i)] - '0') * (i % 2 ? 3 : 1);
  return d12 + static_cast<char>('0' + (10 - sum % 10) % 10);
}

cv::Matx33d translate(double x, double y) { return {1, 0, x, 0, 1, y, 0, 0, 1}; }

cv::Point2d project(const cv::Matx33d& H, cv::Point2d p) {
  const cv::Vec3d v = H * cv::Vec3d(p.x, p.y, 1.0);
  return {v[0] / v[2], v[1] / v[2]};
}

}  // namespace

WarehouseScene::WarehouseScene(const WarehouseOptions& options) : options_(options) {
  if (options.frames < 2 || options.frames > 200000)
    throw InputError("--frames: expected 2..200000, got " + std::to_string(options.frames));
  if (options.size.width < 160 || options.size.height < 120 || options.size.width > 7680 || options.size.height > 4320)
    throw InputError("--size: expected between 160x120 and 7680x4320");
  if (options.location_labels < 6 || options.location_labels > 36 || options.location_labels % 6 != 0)
    throw InputError("--labels: expected a multiple of 6 from 6 to 36 (6 labels per rack bay), got " +
                     std::to_string(options.location_labels));
  if (options.format != "avi" && options.format != "png")
    throw InputError("--format: expected avi or png, got '" + options.format + "'");
  build_world(options.seed);
  build_path(options.seed);
}

void WarehouseScene::build_world(std::uint64_t seed) {
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ULL + 17);
  const int bays = options_.location_labels / 6;
  const int W = 2 * kMarginX + bays * kBayW;
  const int H = kMarginTop + 3 * kLevelH + kFloor;
  content_ = cv::Rect2d(kMarginX, kMarginTop, bays * kBayW, 3 * kLevelH);
  world_.create(H, W, CV_8UC3);
  // Back wall with a coarse texture.
  cv::Mat noise(H / 8 + 1, W / 8 + 1, CV_8UC1);
  for (int y = 0; y < noise.rows; ++y)
    for (int x = 0; x < noise.cols; ++x) noise.at<uchar>(y, x) = static_cast<uchar>(70 + 30 * unit(rng));
  cv::Mat wall;
  cv::resize(noise, wall, world_.size(), 0, 0, cv::INTER_LINEAR);
  cv::cvtColor(wall, world_, cv::COLOR_GRAY2BGR);
  cv::rectangle(world_, cv::Rect(0, H - kFloor + 40, W, kFloor), cv::Scalar(95, 100, 105), cv::FILLED);

  auto paste = [&](const cv::Mat& gray, cv::Point at) {
    const cv::Rect r(at, gray.size());
    cv::Mat bgr;
    cv::cvtColor(gray, bgr, cv::COLOR_GRAY2BGR);
    bgr.copyTo(world_(r & cv::Rect(0, 0, W, H)));
  };

  int product_no = 0;
  for (int bay = 0; bay < bays; ++bay) {
    const int bx = kMarginX + bay * kBayW;
    for (int level = 0; level < 3; ++level) {
      const int top = kMarginTop + (2 - level) * kLevelH;  // level 0 (A) at the bottom
      const int beam_y = top + kLevelH - kBeamH;
      // Boxes standing on this level's beam, repetitive sizes and colours.
      int x = bx + kPostW + 20;
      while (x < bx + kBayW - 150) {
        const int w = static_cast<int>(uniform(rng, 220, 460));
        const int h = static_cast<int>(uniform(rng, 200, kLevelH - kBeamH - 50));
        if (x + w > bx + kBayW - kPostW / 2 - 10) break;
        const cv::Rect box(x, beam_y - h, w, h);
        const double tone = uniform(rng, 0.8, 1.1);
        cv::rectangle(world_, box, cv::Scalar(70 * tone, 120 * tone, 165 * tone), cv::FILLED);
        cv::rectangle(world_, box, cv::Scalar(40, 70, 100), 3);
        cv::rectangle(world_, cv::Rect(x + w / 2 - 18, beam_y - h, 36, h), cv::Scalar(95, 150, 190), cv::FILLED);
        // Printed marks: dark stripes that look a little like bars (clutter for the detector).
        if (unit(rng) < 0.5) {
          for (int k = 0; k < 5; ++k)
            cv::rectangle(world_, cv::Rect(x + 20 + k * 14, beam_y - h + 30, 7, 40), cv::Scalar(30, 45, 60), cv::FILLED);
        }
        if (options_.product_labels && unit(rng) < 0.45) {
          WarehouseLabel label;
          label.kind = "product";
          const int which = product_no++ % 3;
          cv::Mat sym;
          if (which == 0) {
            std::string d;
            for (int k = 0; k < 12; ++k) d += static_cast<char>('0' + static_cast<int>(unit(rng) * 10) % 10);
            if (d[0] == '0') d[0] = '4';
            label.text = ean13_with_check(d);
            label.symbology = "EAN-13";
            label.module_world = 3;
            sym = render_symbol(d, BARCODE_EANX, label.module_world, 40);
          } else if (which == 1) {
            label.text = "P" + std::to_string(100000 + static_cast<int>(unit(rng) * 899999));
            label.symbology = "Code39";
            label.module_world = 2;
            sym = render_symbol(label.text, BARCODE_CODE39, label.module_world, 30);
          } else {
            label.text = "SKU-" + std::to_string(10000 + static_cast<int>(unit(rng) * 89999));
            label.symbology = "Code128";
            label.module_world = 2;
            sym = render_symbol(label.text, BARCODE_CODE128, label.module_world, 30);
          }
          if (sym.cols + 10 < w && sym.rows + 10 < h - 40) {
            const cv::Point at(x + (w - sym.cols) / 2, beam_y - h + 60 + static_cast<int>(unit(rng) * std::max(1, h - sym.rows - 90)));
            cv::rectangle(world_, cv::Rect(at - cv::Point(6, 6), sym.size() + cv::Size(12, 12)), cv::Scalar(235, 235, 235),
                          cv::FILLED);
            paste(sym, at);
            label.bars = cv::Rect2f(static_cast<float>(at.x), static_cast<float>(at.y), static_cast<float>(sym.cols),
                                    static_cast<float>(sym.rows));
            label.modules = static_cast<int>(std::lround(sym.cols / label.module_world));
            labels_.push_back(label);
          }
        }
        x += w + static_cast<int>(uniform(rng, 15, 60));
      }
      // The beam, then the location labels on it (one per column).
      cv::rectangle(world_, cv::Rect(bx, beam_y, kBayW, kBeamH), cv::Scalar(0, 105, 225), cv::FILLED);
      cv::line(world_, cv::Point(bx, beam_y + kBeamH - 4), cv::Point(bx + kBayW, beam_y + kBeamH - 4),
               cv::Scalar(0, 70, 160), 5);
      for (int col = 0; col < 2; ++col) {
        WarehouseLabel label;
        label.kind = "location";
        char text[48];
        std::snprintf(text, sizeof text, "RM%02d%02d%c", 14 + bay, col + 1, static_cast<char>('A' + level));
        label.text = text;
        label.symbology = "Code128";
        label.module_world = 3;
        const cv::Mat sym = render_symbol(label.text, BARCODE_CODE128, label.module_world, 22);
        const int cx = bx + kBayW / 4 + col * kBayW / 2;
        const cv::Point at(cx - sym.cols / 2, beam_y + kBeamH / 2 - sym.rows / 2);
        cv::rectangle(world_, cv::Rect(at - cv::Point(8, 8), sym.size() + cv::Size(16, 16)), cv::Scalar(245, 245, 245),
                      cv::FILLED);
        paste(sym, at);
        label.bars = cv::Rect2f(static_cast<float>(at.x), static_cast<float>(at.y), static_cast<float>(sym.cols),
                                static_cast<float>(sym.rows));
        label.modules = static_cast<int>(std::lround(sym.cols / label.module_world));
        labels_.push_back(label);
      }
    }
    // Uprights at both sides of the bay.
    for (int side = 0; side < 2; ++side) {
      const int px = side == 0 ? bx : bx + kBayW - kPostW;
      cv::rectangle(world_, cv::Rect(px, kMarginTop - 80, kPostW, 3 * kLevelH + 120), cv::Scalar(150, 80, 20), cv::FILLED);
      for (int hy = kMarginTop - 60; hy < kMarginTop + 3 * kLevelH; hy += 50)
        cv::rectangle(world_, cv::Rect(px + 22, hy, 16, 24), cv::Scalar(60, 30, 10), cv::FILLED);
    }
  }
  // Baked light: smooth variation, shadows under beams and diagonal shadow bands that cross labels.
  world_light_.create(H / 4 + 1, W / 4 + 1, CV_32F);
  const double ph1 = uniform(rng, 0, 2 * std::numbers::pi), ph2 = uniform(rng, 0, 2 * std::numbers::pi);
  std::vector<double> bands;
  for (double x = kMarginX + uniform(rng, 0, 900); x < W; x += uniform(rng, 900, 1700)) bands.push_back(x);
  for (int y = 0; y < world_light_.rows; ++y)
    for (int x = 0; x < world_light_.cols; ++x) {
      const double wx = 4.0 * x, wy = 4.0 * y;
      double l = 0.95 + 0.12 * std::sin(wx / 1300.0 + ph1) + 0.08 * std::sin(wy / 500.0 + ph2);
      // Shadow under each beam on the boxes below.
      for (int level = 0; level < 3; ++level) {
        const double by = kMarginTop + (2 - level) * kLevelH - kBeamH + kBeamH;  // beam bottom of level above
        const double d = wy - by;
        if (level < 2 && d > 0 && d < 120) l *= 0.6 + 0.4 * d / 120.0;
      }
      for (double bx : bands) {
        const double u = (wx - bx) + 0.6 * (wy - kMarginTop);  // tilted band
        if (u > 0 && u < 220) l *= 0.55;
      }
      world_light_.at<float>(y, x) = static_cast<float>(std::clamp(l, 0.2, 1.2));
    }
  cv::Mat light_full;
  cv::resize(world_light_, light_full, world_.size(), 0, 0, cv::INTER_LINEAR);
  std::vector<cv::Mat> ch;
  cv::split(world_, ch);
  for (auto& c : ch) {
    cv::Mat f;
    c.convertTo(f, CV_32F);
    f = f.mul(light_full);
    f.convertTo(c, CV_8U);
  }
  cv::merge(ch, world_);
}

double WarehouseScene::light_at_world(const cv::Point2f& p) const {
  const int x = std::clamp(static_cast<int>(p.x / 4.0f), 0, world_light_.cols - 1);
  const int y = std::clamp(static_cast<int>(p.y / 4.0f), 0, world_light_.rows - 1);
  return world_light_.at<float>(y, x);
}

void WarehouseScene::build_path(std::uint64_t seed) {
  std::mt19937_64 rng(seed * 0xD1B54A32D192ED03ULL + 5);
  const int N = options_.frames;
  const double Wf = options_.size.width, Hf = options_.size.height;
  const double view_w = Wf / kNominalScale, view_h = Hf / kNominalScale;
  // Rows of the sweep: enough to see every level at the nominal zoom.
  const int rows = std::max(1, static_cast<int>(std::ceil(content_.height / (0.8 * view_h))));
  std::vector<cv::Point2d> way;
  const double x0 = content_.x + 0.25 * view_w, x1 = content_.x + content_.width - 0.25 * view_w;
  for (int r = 0; r < rows; ++r) {
    const double y = rows == 1 ? content_.y + content_.height / 2
                               : content_.y + 0.4 * view_h + r * (content_.height - 0.8 * view_h) / (rows - 1);
    const double a = r % 2 ? x1 : x0, b = r % 2 ? x0 : x1;
    way.push_back({a, y});
    way.push_back({a + 0.62 * (b - a), y});  // revisit: back a little, then on
    way.push_back({a + 0.45 * (b - a), y});
    way.push_back({b, y});
  }
  const cv::Point2d last = way.back();
  way.push_back({last.x + (rows % 2 ? -0.3 : 0.3) * (x1 - x0), last.y});  // final revisit
  std::vector<double> cum{0};
  for (std::size_t i = 1; i < way.size(); ++i) cum.push_back(cum.back() + cv::norm(way[i] - way[i - 1]));
  // Speed changes: a positive speed profile integrated over the frames.
  const double p1 = uniform(rng, 0, 2 * std::numbers::pi), p2 = uniform(rng, 0, 2 * std::numbers::pi), p3 = uniform(rng, 0, 2 * std::numbers::pi);
  const double p4 = uniform(rng, 0, 2 * std::numbers::pi), p5 = uniform(rng, 0, 2 * std::numbers::pi), p6 = uniform(rng, 0, 2 * std::numbers::pi);
  std::vector<double> dist(static_cast<std::size_t>(N), 0.0);
  for (int t = 1; t < N; ++t) {
    const double v = std::max(0.15, 1.0 + 0.75 * std::sin(2 * std::numbers::pi * t / (N / 3.1) + p1));
    dist[static_cast<std::size_t>(t)] = dist[static_cast<std::size_t>(t) - 1] + v;
  }
  const double total = cum.back();
  for (auto& d : dist) d *= total / dist.back();
  auto at = [&](double d) {
    std::size_t k = 1;
    while (k + 1 < cum.size() && cum[k] < d) ++k;
    const double seg = std::max(1e-9, cum[k] - cum[k - 1]);
    const double u = std::clamp((d - cum[k - 1]) / seg, 0.0, 1.0);
    return way[k - 1] + (way[k] - way[k - 1]) * u;
  };
  auto centre = [&](double t) {
    const double d = std::clamp(t, 0.0, static_cast<double>(N - 1));
    const auto i0 = static_cast<std::size_t>(std::floor(d));
    const auto i1 = std::min(i0 + 1, static_cast<std::size_t>(N - 1));
    const double f = d - static_cast<double>(i0);
    cv::Point2d c = at(dist[i0] * (1 - f) + dist[i1] * f);
    // Handheld left-right shake and a little bounce.
    c.x += 45.0 * std::sin(2 * std::numbers::pi * t / 23.0 + p2) + 12.0 * std::sin(2 * std::numbers::pi * t / 7.3 + p3);
    c.y += 12.0 * std::sin(2 * std::numbers::pi * t / 31.0 + p4);
    return c;
  };
  cameras_.resize(static_cast<std::size_t>(N));
  for (int t = 0; t < N; ++t) {
    WarehouseCamera& cam = cameras_[static_cast<std::size_t>(t)];
    const cv::Point2d c = centre(t);
    cam.x = c.x;
    cam.y = c.y;
    cam.scale = kNominalScale * (1.0 + 0.16 * std::sin(2 * std::numbers::pi * t / (N / 2.3) + p5));
    const double env = std::abs(std::sin(2 * std::numbers::pi * t / (N / 1.6) + p6));
    cam.roll_deg = std::clamp(58.0 * std::sin(2 * std::numbers::pi * t / (N / 3.7) + p1) * env, -45.0, 45.0);
    const double ax = 0.10 / (Wf / 2) * std::sin(2 * std::numbers::pi * t / (N / 1.7) + p3);
    const double ay = 0.06 / (Hf / 2) * std::sin(2 * std::numbers::pi * t / (N / 1.3) + p4);
    const double r = cam.roll_deg * std::numbers::pi / 180.0;
    const cv::Matx33d R(std::cos(r), -std::sin(r), 0, std::sin(r), std::cos(r), 0, 0, 0, 1);
    const cv::Matx33d S(cam.scale, 0, 0, 0, cam.scale, 0, 0, 0, 1);
    const cv::Matx33d P(1, 0, 0, 0, 1, 0, ax, ay, 1);
    cam.H = translate(Wf / 2, Hf / 2) * P * R * S * translate(-c.x, -c.y);
    // Motion blur: the image motion of the centre during a 40 % exposure.
    const cv::Point2d v = (centre(t + 0.5) - centre(t - 0.5)) * 0.4;
    cam.blur = cv::Point2d(std::cos(r) * v.x - std::sin(r) * v.y, std::sin(r) * v.x + std::cos(r) * v.y) * cam.scale;
    cam.defocus = std::max(0.0, 3.4 * std::sin(2 * std::numbers::pi * t / (N / 4.3) + p2) - 2.0);
    cam.light = 0.88 + 0.14 * std::sin(2 * std::numbers::pi * t / (N / 2.1) + p5);
    cam.light_gradient = {0.22 / Wf * std::sin(2 * std::numbers::pi * t / (N / 1.9) + p6), 0.12 / Hf * std::sin(2 * std::numbers::pi * t / (N / 2.9))};
  }
}

cv::Mat WarehouseScene::render(int i) const {
  const WarehouseCamera& cam = cameras_.at(static_cast<std::size_t>(i));
  cv::Mat frame;
  cv::warpPerspective(world_, frame, cam.H, options_.size, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(35, 35, 35));
  const double blur_len = cv::norm(cam.blur);
  if (blur_len > 1.2) {
    const int k = 2 * static_cast<int>(std::ceil(blur_len / 2)) + 1;
    cv::Mat kernel = cv::Mat::zeros(k, k, CV_32F);
    const cv::Point2d c(k / 2.0, k / 2.0);
    const int steps = 4 * k;
    for (int s = 0; s <= steps; ++s) {
      const cv::Point2d p = c + cam.blur * (static_cast<double>(s) / steps - 0.5);
      kernel.at<float>(std::clamp(static_cast<int>(p.y), 0, k - 1), std::clamp(static_cast<int>(p.x), 0, k - 1)) += 1.0f;
    }
    kernel /= cv::sum(kernel)[0];
    cv::filter2D(frame, frame, -1, kernel, cv::Point(-1, -1), 0, cv::BORDER_REPLICATE);
  }
  if (cam.defocus > 0.3) cv::GaussianBlur(frame, frame, cv::Size(), cam.defocus);
  // Exposure with a gradient across the frame, then sensor noise.
  cv::Mat noise(frame.size(), CV_16SC3);
  cv::RNG rng(options_.seed * 1000003ULL + static_cast<std::uint64_t>(i));
  rng.fill(noise, cv::RNG::NORMAL, 0, 2.0);
  const double cx = frame.cols / 2.0, cy = frame.rows / 2.0;
  for (int y = 0; y < frame.rows; ++y) {
    auto* p = frame.ptr<uchar>(y);
    const auto* n = noise.ptr<short>(y);
    const double ly = cam.light + cam.light_gradient.y * (y - cy);
    for (int x = 0; x < frame.cols; ++x) {
      const double l = ly + cam.light_gradient.x * (x - cx);
      for (int ch = 0; ch < 3; ++ch) {
        const int idx = 3 * x + ch;
        p[idx] = cv::saturate_cast<uchar>(p[idx] * l + n[idx]);
      }
    }
  }
  return frame;
}

bool WarehouseScene::visible(std::size_t l, int i) const {
  const auto& cam = cameras_.at(static_cast<std::size_t>(i));
  const cv::Rect2f& b = labels_.at(l).bars;
  std::vector<cv::Point2f> q;
  for (const auto& p : {b.tl(), cv::Point2f(b.x + b.width, b.y), b.br(), cv::Point2f(b.x, b.y + b.height)})
    q.push_back(cv::Point2f(project(cam.H, p)));
  const cv::Rect box = cv::boundingRect(q);
  return (box & cv::Rect(0, 0, options_.size.width, options_.size.height)).area() > 0;
}

bool WarehouseScene::legible(std::size_t l, int i) const {
  const auto& cam = cameras_.at(static_cast<std::size_t>(i));
  const WarehouseLabel& label = labels_.at(l);
  const cv::Rect2f& b = label.bars;
  const cv::Point2f corners[4] = {b.tl(), cv::Point2f(b.x + b.width, b.y), b.br(), cv::Point2f(b.x, b.y + b.height)};
  cv::Point2d q[4];
  for (int k = 0; k < 4; ++k) {
    q[k] = project(cam.H, corners[k]);
    if (q[k].x < 2 || q[k].y < 2 || q[k].x > options_.size.width - 3 || q[k].y > options_.size.height - 3) return false;
  }
  const cv::Point2d along = ((q[1] - q[0]) + (q[2] - q[3])) * 0.5;
  const double len = cv::norm(along);
  const double module = len / std::max(1, label.modules);
  if (module < 1.5) return false;
  const cv::Point2d u = along / len;
  const double blur_across = std::abs(cam.blur.dot(u));
  if (blur_across > 1.2 * module) return false;
  if (cam.defocus > 0.5 * module) return false;
  double light = 10;
  for (int k = 0; k < 4; ++k) {
    const cv::Point2d d = q[k] - cv::Point2d(options_.size.width / 2.0, options_.size.height / 2.0);
    const double frame_light = cam.light + cam.light_gradient.x * d.x + cam.light_gradient.y * d.y;
    light = std::min(light, light_at_world(corners[k]) * frame_light);
  }
  light = std::min(light, light_at_world((corners[0] + corners[2]) * 0.5f) * cam.light);
  return light >= 0.3;
}

cv::Mat render_barcode(const std::string& text, const std::string& symbology, int module, int height_modules) {
  if (module < 1 || module > 20) throw InputError("render_barcode: module must be 1..20 pixels");
  int sym = 0;
  std::string data = text;
  if (symbology == "Code128") {
    sym = BARCODE_CODE128;
  } else if (symbology == "Code39") {
    sym = BARCODE_CODE39;
  } else if (symbology == "EAN-13") {
    sym = BARCODE_EANX;
    if (data.size() == 13) data = data.substr(0, 12);  // zint adds the check digit
  } else {
    throw InputError("render_barcode: unsupported symbology '" + symbology + "'");
  }
  return render_symbol(data, sym, static_cast<float>(module), static_cast<float>(height_modules));
}

WarehouseWriteResult write_warehouse_scan(const fs::path& dir, const WarehouseOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const WarehouseScene scene(options);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw InputError(located(dir, 0, "cannot create output folder: " + ec.message()));
  WarehouseWriteResult res;
  cv::VideoWriter writer;
  if (options.format == "avi") {
    res.video = dir / "scan.avi";
    // FFmpeg's MJPG encoder: standard JPEG packets that the scan can decode on its own threads.
    writer.open(res.video.string(), cv::CAP_FFMPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 30.0, options.size);
    if (!writer.isOpened()) throw Failure(located(res.video, 0, "cannot open an MJPG video writer"));
  } else {
    res.video = dir / "frames";
    fs::create_directories(res.video, ec);
    if (ec) throw Failure(located(res.video, 0, "cannot create folder: " + ec.message()));
  }
  // Frames render in parallel batches and are written in order.
  const int threads = std::max(1, options.threads);
  const int batch = 4 * threads;
  std::vector<cv::Mat> frames(static_cast<std::size_t>(batch));
  for (int start = 0; start < options.frames; start += batch) {
    const int n = std::min(batch, options.frames - start);
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t)
      pool.emplace_back([&, t] {
        for (int k = t; k < n; k += threads) frames[static_cast<std::size_t>(k)] = scene.render(start + k);
      });
    for (auto& th : pool) th.join();
    for (int k = 0; k < n; ++k) {
      if (options.format == "avi") {
        writer.write(frames[static_cast<std::size_t>(k)]);
      } else {
        char name[32];
        std::snprintf(name, sizeof name, "%06d.png", start + k);
        if (!cv::imwrite((res.video / name).string(), frames[static_cast<std::size_t>(k)]))
          throw Failure(located(res.video / name, 0, "cannot write frame"));
      }
    }
  }
  writer.release();

  auto ranges = [](const std::vector<int>& f) {
    std::string s;
    for (std::size_t i = 0; i < f.size();) {
      std::size_t j = i;
      while (j + 1 < f.size() && f[j + 1] == f[j] + 1) ++j;
      if (!s.empty()) s += ';';
      s += std::to_string(f[i]);
      if (j > i) s += "-" + std::to_string(f[j]);
      i = j + 1;
    }
    return s;
  };
  res.truth = dir / "truth.csv";
  std::ofstream truth(res.truth);
  truth << "text,symbology,kind,x,y,module_px_world,legible_count,visible_frames,legible_frames\n";
  for (std::size_t l = 0; l < scene.labels().size(); ++l) {
    const auto& label = scene.labels()[l];
    std::vector<int> vis, leg;
    for (int i = 0; i < options.frames; ++i) {
      if (scene.visible(l, i)) vis.push_back(i);
      if (scene.legible(l, i)) leg.push_back(i);
    }
    truth << label.text << ',' << label.symbology << ',' << label.kind << ',' << static_cast<int>(label.bars.x) << ','
          << static_cast<int>(label.bars.y) << ',' << label.module_world << ',' << leg.size() << ',' << ranges(vis)
          << ',' << ranges(leg) << '\n';
    ++res.labels;
    if (label.kind == "location") ++res.location_labels;
    if (!leg.empty()) ++res.legible_labels;
  }
  if (!truth) throw Failure(located(res.truth, 0, "cannot write"));
  std::ofstream camera(dir / "camera.csv");
  camera << "frame,x,y,scale,roll_deg,blur_x,blur_y,defocus,light\n";
  for (std::size_t i = 0; i < scene.cameras().size(); ++i) {
    const auto& c = scene.cameras()[i];
    camera << i << ',' << c.x << ',' << c.y << ',' << c.scale << ',' << c.roll_deg << ',' << c.blur.x << ',' << c.blur.y
           << ',' << c.defocus << ',' << c.light << '\n';
  }
  res.frames = options.frames;
  res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

}  // namespace builtscene::synth
