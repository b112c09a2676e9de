#include "synth/texture_generator.hpp"

#include <cmath>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace builtscene::synth {
namespace {

// Multi-octave value noise in about [-1, 1]: random grids upsampled bicubically and summed.
cv::Mat fractal(cv::RNG& rng, int w, int h, int first_cells, double persistence, int octaves) {
  cv::Mat acc(h, w, CV_32F, cv::Scalar(0));
  double amp = 1.0, total = 0.0;
  int cells = first_cells;
  for (int o = 0; o < octaves && cells <= std::max(w, h); ++o) {
    cv::Mat g(std::max(2, cells * h / std::max(w, h)), cells, CV_32F);
    rng.fill(g, cv::RNG::UNIFORM, -1.0, 1.0);
    cv::Mat up;
    cv::resize(g, up, cv::Size(w, h), 0, 0, cv::INTER_CUBIC);
    acc += up * amp;
    total += amp;
    amp *= persistence;
    cells *= 2;
  }
  return acc / total;
}

cv::Mat colorize(const cv::Mat& f, cv::Scalar base, double contrast) {
  std::vector<cv::Mat> ch(3);
  for (int c = 0; c < 3; ++c) f.convertTo(ch[c], CV_8U, contrast, base[c]);
  cv::Mat out;
  cv::merge(ch, out);
  return out;
}

cv::Scalar random_color(cv::RNG& rng, int lo = 20, int hi = 235) {
  return cv::Scalar(rng.uniform(lo, hi), rng.uniform(lo, hi), rng.uniform(lo, hi));
}

std::string random_word(cv::RNG& rng, int min_len, int max_len) {
  static const char* letters = "ABCDEFGHIJKLMNOPRSTUEAIOaeioubcdfghklmnprstuvwyz";
  const int n = rng.uniform(min_len, max_len + 1);
  std::string s;
  for (int i = 0; i < n; ++i) s += letters[rng.uniform(0, 48)];
  return s;
}

void text_lines(cv::Mat& img, cv::RNG& rng, cv::Rect area, double scale, cv::Scalar color, int lines) {
  const int line_h = static_cast<int>(28 * scale) + 4;
  for (int l = 0; l < lines; ++l) {
    int x = area.x;
    const int y = area.y + (l + 1) * line_h;
    if (y > area.y + area.height) break;
    while (x < area.x + area.width - 20) {
      const std::string w = random_word(rng, 2, 8);
      int base = 0;
      const cv::Size sz = cv::getTextSize(w, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &base);
      if (x + sz.width > area.x + area.width) break;
      cv::putText(img, w, cv::Point(x, y), cv::FONT_HERSHEY_SIMPLEX, scale, color, scale > 0.8 ? 2 : 1, cv::LINE_AA);
      x += sz.width + static_cast<int>(12 * scale);
    }
  }
}

cv::Mat paint(cv::RNG& rng, int s, cv::Scalar base) {
  // Plain paint: almost uniform, a faint roller pattern and grain.
  cv::Mat f = fractal(rng, s, s, 3, 0.5, 5);
  cv::Mat g(s, s, CV_32F);
  rng.fill(g, cv::RNG::NORMAL, 0.0, 0.25);
  return colorize(f * 3.0 + g, base, 1.0);
}

cv::Mat concrete(cv::RNG& rng, int s, cv::Scalar base) {
  cv::Mat f = fractal(rng, s, s, 4, 0.6, 7);
  cv::Mat img = colorize(f, base, 28.0);
  for (int i = 0; i < s * s / 900; ++i) {  // pores and small stains
    const cv::Point p(rng.uniform(0, s), rng.uniform(0, s));
    const int shade = rng.uniform(-50, -10);
    cv::circle(img, p, rng.uniform(1, 3), base + cv::Scalar(shade, shade, shade), -1, cv::LINE_AA);
  }
  for (int i = 0; i < 3; ++i) {
    cv::Mat stain = img.clone();
    cv::ellipse(stain, cv::Point(rng.uniform(0, s), rng.uniform(0, s)), cv::Size(rng.uniform(20, s / 4), rng.uniform(20, s / 4)),
                rng.uniform(0, 180), 0, 360, base * 0.8, -1, cv::LINE_AA);
    cv::addWeighted(img, 0.7, stain, 0.3, 0, img);
  }
  return img;
}

cv::Mat tiles(cv::RNG& rng, int s, cv::Scalar base, int n, int grout, double speckle, bool dots) {
  cv::Mat img(s, s, CV_8UC3);
  const int t = s / n;
  cv::Mat noise = fractal(rng, s, s, 8, 0.6, 6);
  for (int ty = 0; ty < n; ++ty)
    for (int tx = 0; tx < n; ++tx) {
      const double v = rng.uniform(-12.0, 12.0);
      img(cv::Rect(tx * t, ty * t, t, t)).setTo(base + cv::Scalar(v, v, v * 0.8));
    }
  cv::Mat nz = colorize(noise, cv::Scalar(0, 0, 0), 10.0);
  cv::add(img, nz, img);
  for (int i = 0; i < static_cast<int>(speckle * s * s / 100); ++i) {
    const cv::Point p(rng.uniform(0, s), rng.uniform(0, s));
    cv::circle(img, p, rng.uniform(1, 3), rng.uniform(0, 2) ? base * 0.6 : base * 1.15, -1, cv::LINE_AA);
  }
  if (dots)
    for (int y = 4; y < s; y += 9)
      for (int x = 4 + (y / 9 % 2) * 4; x < s; x += 9)
        if (rng.uniform(0, 10) < 7) cv::circle(img, cv::Point(x + rng.uniform(-2, 3), y + rng.uniform(-2, 3)), 1, base * 0.55, -1);
  for (int k = 0; k <= n; ++k) {
    const int p = k * t;
    cv::line(img, cv::Point(p, 0), cv::Point(p, s), base * 0.55, grout);
    cv::line(img, cv::Point(0, p), cv::Point(s, p), base * 0.55, grout);
  }
  return img;
}

cv::Mat wood(cv::RNG& rng, int s, cv::Scalar base) {
  cv::Mat warp = fractal(rng, s, s, 3, 0.5, 4);
  cv::Mat fine = fractal(rng, s, s, 64, 0.5, 3);
  cv::Mat f(s, s, CV_32F);
  const double freq = rng.uniform(0.12, 0.2);
  for (int y = 0; y < s; ++y)
    for (int x = 0; x < s; ++x) {
      const double g = std::sin(y * freq + 9.0 * warp.at<float>(y, x) + 0.02 * x);
      f.at<float>(y, x) = static_cast<float>(0.6 * g * g * g + 0.4 * fine.at<float>(y, x));
    }
  cv::Mat img = colorize(f, base, 35.0);
  // Plank joints.
  const int planks = rng.uniform(3, 6);
  for (int k = 1; k < planks; ++k) cv::line(img, cv::Point(0, k * s / planks), cv::Point(s, k * s / planks), base * 0.5, 2);
  return img;
}

cv::Mat carpet(cv::RNG& rng, int s, cv::Scalar base) {
  cv::Mat f = fractal(rng, s, s, 128, 0.8, 3);
  cv::Mat c = fractal(rng, s, s, 6, 0.5, 3);
  return colorize(f * 0.7 + c * 0.3, base, 30.0);
}

cv::Mat metal(cv::RNG& rng, int s, cv::Scalar base) {
  cv::Mat f(s, s, CV_32F);
  rng.fill(f, cv::RNG::NORMAL, 0.0, 1.0);
  cv::Mat brushed;
  cv::blur(f, brushed, cv::Size(41, 1));
  cv::Mat shade = fractal(rng, s, s, 2, 0.5, 2);
  return colorize(brushed * 0.6 + shade * 0.8, base, 12.0);
}

void random_shapes(cv::Mat& img, cv::RNG& rng, cv::Rect area, int count) {
  for (int i = 0; i < count; ++i) {
    const cv::Point c(area.x + rng.uniform(0, area.width), area.y + rng.uniform(0, area.height));
    const int r = rng.uniform(6, std::max(8, area.width / 6));
    switch (rng.uniform(0, 4)) {
      case 0: cv::circle(img, c, r, random_color(rng), -1, cv::LINE_AA); break;
      case 1: cv::rectangle(img, c, c + cv::Point(r, r * rng.uniform(1, 3) / 2), random_color(rng), -1); break;
      case 2: {
        std::vector<cv::Point> pts;
        for (int k = 0; k < 3; ++k) pts.push_back(c + cv::Point(rng.uniform(-r, r), rng.uniform(-r, r)));
        cv::fillConvexPoly(img, pts, random_color(rng), cv::LINE_AA);
        break;
      }
      default: cv::line(img, c, c + cv::Point(rng.uniform(-r, r), rng.uniform(-r, r)), random_color(rng), rng.uniform(1, 5), cv::LINE_AA);
    }
  }
  img(area) &= cv::Scalar(255, 255, 255);
}

cv::Mat poster(cv::RNG& rng, int s) {
  const int w = s, h = s * 4 / 3;
  cv::Mat img(h, w, CV_8UC3, random_color(rng, 120, 250));
  // A "photograph": coloured fractal landscape with shapes.
  const cv::Rect photo(w / 10, h / 6, w * 8 / 10, h * 4 / 10);
  std::vector<cv::Mat> ch(3);
  for (int c = 0; c < 3; ++c) fractal(rng, photo.width, photo.height, 4, 0.65, 6).convertTo(ch[c], CV_8U, 90, rng.uniform(70, 180));
  cv::Mat ph;
  cv::merge(ch, ph);
  ph.copyTo(img(photo));
  random_shapes(img, rng, photo, rng.uniform(5, 25));
  cv::rectangle(img, photo, cv::Scalar(30, 30, 30), 2);
  cv::putText(img, random_word(rng, 4, 9), cv::Point(w / 10, h / 8), cv::FONT_HERSHEY_DUPLEX, 1.6 * s / 512, random_color(rng, 0, 90), 3,
              cv::LINE_AA);
  text_lines(img, rng, cv::Rect(w / 10, h * 6 / 10, w * 8 / 10, h * 3 / 10), 0.55 * s / 512, cv::Scalar(20, 20, 20), 8);
  if (rng.uniform(0, 2)) {  // a chart
    for (int k = 0; k < 6; ++k) {
      const int bh = rng.uniform(10, h / 10);
      cv::rectangle(img, cv::Rect(w * 6 / 10 + k * w / 20, h * 19 / 20 - bh, w / 30, bh), random_color(rng, 0, 200), -1);
    }
  }
  cv::rectangle(img, cv::Rect(0, 0, w, h), cv::Scalar(40, 40, 40), 3);
  return img;
}

cv::Mat whiteboard(cv::RNG& rng, int s) {
  const int w = s * 2, h = s;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(238, 240, 240));
  for (int i = 0; i < 6; ++i) {  // marker scribbles
    std::vector<cv::Point> pts;
    cv::Point p(rng.uniform(w / 10, w * 9 / 10), rng.uniform(h / 10, h * 9 / 10));
    for (int k = 0; k < 12; ++k) {
      p += cv::Point(rng.uniform(-25, 26), rng.uniform(-15, 16));
      pts.push_back(p);
    }
    cv::polylines(img, pts, false, random_color(rng, 0, 160), 2, cv::LINE_AA);
  }
  text_lines(img, rng, cv::Rect(w / 20, h / 20, w / 2, h * 8 / 10), 0.7 * s / 512, cv::Scalar(120, 40, 20), 6);
  cv::rectangle(img, cv::Rect(0, 0, w, h), cv::Scalar(150, 150, 150), 8);
  return img;
}

cv::Mat books(cv::RNG& rng, int s) {
  cv::Mat img(s, s, CV_8UC3, cv::Scalar(60, 90, 120));
  const int rows = 4;
  const int rh = s / rows;
  for (int r = 0; r < rows; ++r) {
    int x = 4;
    while (x < s - 8) {
      const int bw = rng.uniform(8, 26);
      const int bh = rng.uniform(rh * 6 / 10, rh - 10);
      const cv::Scalar c = random_color(rng, 20, 220);
      const cv::Rect b(x, r * rh + rh - 6 - bh, std::min(bw, s - 4 - x), bh);
      cv::rectangle(img, b, c, -1);
      if (rng.uniform(0, 3) == 0) {
        cv::line(img, cv::Point(b.x, b.y + bh / 5), cv::Point(b.x + b.width, b.y + bh / 5), c * 0.4, 2);
        cv::line(img, cv::Point(b.x, b.y + bh * 4 / 5), cv::Point(b.x + b.width, b.y + bh * 4 / 5), c * 0.4, 2);
      }
      if (rng.uniform(0, 2) == 0) cv::rectangle(img, cv::Rect(b.x + 2, b.y + bh / 3, std::max(1, b.width - 4), bh / 4), c * 1.4 + cv::Scalar(30, 30, 30), -1);
      x += bw + rng.uniform(0, 3);
      if (rng.uniform(0, 25) == 0) x += rng.uniform(20, 60);  // a gap
    }
    cv::rectangle(img, cv::Rect(0, r * rh + rh - 6, s, 6), cv::Scalar(40, 70, 100), -1);  // the shelf board
  }
  return img;
}

cv::Mat door(cv::RNG& rng, int s) {
  const int w = s / 2, h = s;
  cv::Mat img = wood(rng, std::max(w, h), cv::Scalar(70, 110, 150))(cv::Rect(0, 0, w, h)).clone();
  cv::rectangle(img, cv::Rect(0, 0, w, h), cv::Scalar(90, 90, 90), 10);                     // frame
  cv::rectangle(img, cv::Rect(w / 8, h / 10, w * 6 / 8, h / 3), cv::Scalar(50, 80, 110), 3);  // panels
  cv::rectangle(img, cv::Rect(w / 8, h / 2, w * 6 / 8, h * 4 / 10), cv::Scalar(50, 80, 110), 3);
  cv::rectangle(img, cv::Rect(w * 3 / 4, h / 2 - 4, w / 8, 8), cv::Scalar(180, 180, 180), -1);  // handle
  cv::rectangle(img, cv::Rect(w / 4, h / 6 - 10, w / 2, 22), cv::Scalar(240, 240, 240), -1);   // room sign
  cv::putText(img, std::to_string(rng.uniform(100, 400)), cv::Point(w / 4 + 4, h / 6 + 8), cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  return img;
}

cv::Mat corkboard(cv::RNG& rng, int s) {
  cv::Mat img = carpet(rng, s, cv::Scalar(80, 130, 170));
  for (int i = 0; i < 10; ++i) {
    const cv::Rect r(rng.uniform(0, s * 3 / 4), rng.uniform(0, s * 3 / 4), rng.uniform(s / 8, s / 4), rng.uniform(s / 8, s / 4));
    const cv::Rect rr = r & cv::Rect(0, 0, s, s);
    img(rr).setTo(random_color(rng, 180, 255));
    text_lines(img, rng, rr, 0.35, cv::Scalar(30, 30, 30), 5);
    cv::circle(img, cv::Point(rr.x + rr.width / 2, rr.y + 4), 4, random_color(rng, 0, 255), -1, cv::LINE_AA);
  }
  return img;
}

cv::Mat screen(cv::RNG& rng, int s) {
  cv::Mat img(s * 9 / 16, s, CV_8UC3, cv::Scalar(30, 25, 25));
  for (int i = 0; i < 4; ++i) {
    const cv::Rect r(rng.uniform(10, s / 2), rng.uniform(10, s / 4), rng.uniform(s / 5, s / 2), rng.uniform(s / 8, s / 4));
    const cv::Rect rr = r & cv::Rect(8, 8, img.cols - 16, img.rows - 16);
    img(rr).setTo(cv::Scalar(235, 235, 235));
    cv::rectangle(img, cv::Rect(rr.x, rr.y, rr.width, 12), random_color(rng, 80, 200), -1);
    text_lines(img, rng, cv::Rect(rr.x + 4, rr.y + 12, rr.width - 8, rr.height - 12), 0.3, cv::Scalar(40, 40, 40), 8);
  }
  cv::rectangle(img, cv::Rect(0, 0, img.cols, img.rows), cv::Scalar(15, 15, 15), 10);
  return img;
}

cv::Mat sign(cv::RNG& rng, int s) {
  const bool exit = rng.uniform(0, 2);
  cv::Mat img(s / 2, s, CV_8UC3, exit ? cv::Scalar(60, 160, 30) : cv::Scalar(245, 245, 245));
  cv::putText(img, exit ? "EXIT" : random_word(rng, 4, 8), cv::Point(s / 10, s / 3), cv::FONT_HERSHEY_DUPLEX, 2.0 * s / 512,
              exit ? cv::Scalar(255, 255, 255) : cv::Scalar(30, 30, 120), 4, cv::LINE_AA);
  cv::arrowedLine(img, cv::Point(s * 6 / 10, s * 4 / 10), cv::Point(s * 9 / 10, s * 4 / 10), exit ? cv::Scalar(255, 255, 255) : cv::Scalar(30, 30, 30), 8);
  return img;
}

cv::Mat brick(cv::RNG& rng, int s, cv::Scalar base) {
  cv::Mat img(s, s, CV_8UC3, base * 0.7);
  const int bh = s / 8, bw = s / 4;
  for (int r = 0; r < 8; ++r)
    for (int c = -1; c < 5; ++c) {
      const int x = c * bw + (r % 2) * bw / 2;
      const double v = rng.uniform(-20.0, 20.0);
      cv::rectangle(img, cv::Rect(x + 3, r * bh + 3, bw - 6, bh - 6), base + cv::Scalar(v, v, v), -1);
    }
  cv::Mat nz = colorize(fractal(rng, s, s, 32, 0.6, 4), cv::Scalar(0, 0, 0), 14.0);
  cv::add(img, nz, img);
  return img;
}

}  // namespace

std::vector<std::string> texture_kinds() {
  return {"paint", "concrete", "floor_tiles", "lino", "ceiling_tiles", "wood", "carpet", "metal",
          "poster", "whiteboard", "books", "door", "corkboard", "screen", "sign", "brick"};
}

cv::Mat generate_texture(const std::string& kind, std::uint64_t seed, int size, cv::Scalar base) {
  cv::RNG rng(seed * 2654435761ull + 12345);
  if (kind == "paint") return paint(rng, size, base);
  if (kind == "concrete") return concrete(rng, size, base);
  if (kind == "floor_tiles") return tiles(rng, size, base, 4, 2, 3.0, false);
  if (kind == "lino") return tiles(rng, size, base, 2, 1, 0.3, false);
  if (kind == "ceiling_tiles") return tiles(rng, size, base, 2, 4, 0.0, true);
  if (kind == "wood") return wood(rng, size, base);
  if (kind == "carpet") return carpet(rng, size, base);
  if (kind == "metal") return metal(rng, size, base);
  if (kind == "poster") return poster(rng, size);
  if (kind == "whiteboard") return whiteboard(rng, size);
  if (kind == "books") return books(rng, size);
  if (kind == "door") return door(rng, size);
  if (kind == "corkboard") return corkboard(rng, size);
  if (kind == "screen") return screen(rng, size);
  if (kind == "sign") return sign(rng, size);
  if (kind == "brick") return brick(rng, size, base);
  throw std::invalid_argument("unknown texture kind " + kind);
}

}  // namespace builtscene::synth
