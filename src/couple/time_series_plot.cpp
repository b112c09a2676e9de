#include "couple/time_series_plot.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/errors.hpp"

namespace builtscene::couple {
namespace {

std::string fmt_num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

}  // namespace

void plot_panels(const std::vector<Panel>& panels, const std::string& x_label, const std::filesystem::path& png) {
  const int W = 1100, H = 190, left = 90, right = 20, top = 28, bottom = 22;
  cv::Mat img(static_cast<int>(panels.size()) * H + 30, W, CV_8UC3, cv::Scalar(255, 255, 255));
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  for (std::size_t p = 0; p < panels.size(); ++p) {
    const Panel& pan = panels[p];
    const int y0 = static_cast<int>(p) * H;
    double xmin = INFINITY, xmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY;
    for (const auto& c : pan.curves)
      for (std::size_t i = 0; i < c.x.size(); ++i) {
        xmin = std::min(xmin, c.x[i]);
        xmax = std::max(xmax, c.x[i]);
        ymin = std::min(ymin, c.y[i]);
        ymax = std::max(ymax, c.y[i]);
      }
    for (double l : pan.limits) {
      ymin = std::min(ymin, l);
      ymax = std::max(ymax, l);
    }
    if (!std::isfinite(xmin)) continue;
    if (ymax - ymin < 1e-300) {
      ymax += 1;
      ymin -= 1;
    }
    const double pad = 0.05 * (ymax - ymin);
    ymin -= pad;
    ymax += pad;
    const cv::Rect area(left, y0 + top, W - left - right, H - top - bottom);
    cv::rectangle(img, area, cv::Scalar(160, 160, 160));
    auto px = [&](double x, double y) {
      return cv::Point(area.x + static_cast<int>(std::lround((x - xmin) / (xmax - xmin) * area.width)),
                       area.y + static_cast<int>(std::lround((ymax - y) / (ymax - ymin) * area.height)));
    };
    if (ymin < 0 && ymax > 0) cv::line(img, px(xmin, 0), px(xmax, 0), cv::Scalar(210, 210, 210));
    for (double l : pan.limits)
      for (double x = xmin; x < xmax; x += (xmax - xmin) / 80)
        cv::line(img, px(x, l), px(std::min(xmax, x + (xmax - xmin) / 160), l), cv::Scalar(0, 0, 200), 1);
    cv::putText(img, pan.title, cv::Point(left, y0 + 20), font, 0.55, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    cv::putText(img, fmt_num(ymax - pad), cv::Point(5, area.y + 12), font, 0.4, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    cv::putText(img, fmt_num(ymin + pad), cv::Point(5, area.y + area.height), font, 0.4, cv::Scalar(0, 0, 0), 1,
                cv::LINE_AA);
    int legend_x = W - right - 10;
    for (auto it = pan.curves.rbegin(); it != pan.curves.rend(); ++it) {
      const auto& c = *it;
      std::vector<cv::Point> pts;
      for (std::size_t i = 0; i < c.x.size(); ++i) pts.push_back(px(c.x[i], c.y[i]));
      cv::polylines(img, pts, false, cv::Scalar(c.b, c.g, c.r), 1, cv::LINE_AA);
      int base = 0;
      const auto sz = cv::getTextSize(c.label, font, 0.45, 1, &base);
      legend_x -= sz.width + 30;
      cv::line(img, cv::Point(legend_x, y0 + 15), cv::Point(legend_x + 20, y0 + 15), cv::Scalar(c.b, c.g, c.r), 2);
      cv::putText(img, c.label, cv::Point(legend_x + 24, y0 + 20), font, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    }
    if (p + 1 == panels.size()) {
      cv::putText(img, fmt_num(xmin), cv::Point(area.x, area.y + area.height + 16), font, 0.4, cv::Scalar(0, 0, 0), 1,
                  cv::LINE_AA);
      cv::putText(img, fmt_num(xmax) + " " + x_label, cv::Point(area.x + area.width - 80, area.y + area.height + 16),
                  font, 0.4, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    }
  }
  if (!cv::imwrite(png.string(), img)) throw Failure(located(png, 0, "cannot write the plot"));
}

}  // namespace builtscene::couple
