#include "core/svg_line_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "core/svg_text.h"

namespace chordfit {

namespace {

// Colour-blind-safe palette (Okabe & Ito, "Color Universal Design", 2008).
const char* const kPalette[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                "#E69F00", "#56B4E9", "#000000", "#F0E442"};

std::string formatTick(double value, double step) {
  char buffer[32];
  const int decimals = std::max(0, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
  std::snprintf(buffer, sizeof buffer, "%.*f", std::min(decimals, 6), value);
  return buffer;
}

// A marker of the given shape and circumradius r at (x, y) px, filled with `colour`; with a
// white rim above 2.5 px.
void drawMarker(std::ostringstream& svg, PlotMarker marker, double x, double y, double r,
                const std::string& colour) {
  const std::string paint =
      "fill='" + colour + "'" + (r > 2.5 ? std::string(" stroke='white' stroke-width='1'") : "");
  char points[160];
  switch (marker) {
    case PlotMarker::kCircle:
      svg << "<circle cx='" << x << "' cy='" << y << "' r='" << r << "' " << paint << "/>\n";
      return;
    case PlotMarker::kSquare: {
      const double h = r / std::sqrt(2.0);
      svg << "<rect x='" << x - h << "' y='" << y - h << "' width='" << 2 * h << "' height='"
          << 2 * h << "' " << paint << "/>\n";
      return;
    }
    case PlotMarker::kDiamond:
      std::snprintf(points, sizeof points, "%.2f,%.2f %.2f,%.2f %.2f,%.2f %.2f,%.2f", x, y - r,
                    x + r, y, x, y + r, x - r, y);
      break;
    case PlotMarker::kTriangleUp:
    case PlotMarker::kTriangleDown: {
      const double s = marker == PlotMarker::kTriangleUp ? 1.0 : -1.0;
      const double half = r * std::sqrt(3.0) / 2.0;
      std::snprintf(points, sizeof points, "%.2f,%.2f %.2f,%.2f %.2f,%.2f", x, y - s * r, x + half,
                    y + s * 0.5 * r, x - half, y + s * 0.5 * r);
      break;
    }
  }
  svg << "<polygon points='" << points << "' " << paint << "/>\n";
}

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  void finish() {
    if (!std::isfinite(lo)) lo = 0.0, hi = 1.0;
    if (hi - lo < 1e-12 * std::max(1.0, std::abs(hi))) {
      const double pad = std::max(1e-9, 0.05 * std::abs(hi));
      lo -= pad;
      hi += pad;
    }
  }
};

// Each axis spans at least the data's range widened by this fraction of it at both ends.
constexpr double kDataPadFraction = 0.03;

void drawPanel(std::ostringstream& svg, const PlotPanel& panel, double left, double top,
               double width, double height) {
  const double margin_left = 70, margin_right = 15 + panel.legend_margin, margin_top = 30,
               margin_bottom = 45;
  const double plot_w = width - margin_left - margin_right;
  const double plot_h = height - margin_top - margin_bottom;
  auto ty = [&](double y) { return panel.log_y ? (y > 0 ? std::log10(y) : NAN) : y; };
  Range xr, yr;
  for (const PlotSeries& s : panel.series) {
    for (double x : s.x) xr.add(x);
    for (double y : s.y) yr.add(ty(y));
  }
  xr.finish();
  yr.finish();
  const std::vector<double> xt = niceTicks(xr.lo, xr.hi);
  // On a log axis the ticks are values (1, 2, 5 x 10^k), placed at their exponents.
  std::vector<double> yt = panel.log_y ? logTicks(yr.lo, yr.hi) : niceTicks(yr.lo, yr.hi);
  if (panel.log_y)
    for (double& y : yt) y = std::log10(y);
  // The axis spans the ticks and the data with room for the markers: a point at the data's
  // extreme sat on the frame when a tick fell just below it (costs of 507 on an axis from 500:
  // half of each marker clipped). The room is not ticked (no "-50" forward runs).
  const double x_pad = kDataPadFraction * (xr.hi - xr.lo);
  const double y_pad = kDataPadFraction * (yr.hi - yr.lo);
  xr.lo = std::min(xr.lo - x_pad, xt.front()), xr.hi = std::max(xr.hi + x_pad, xt.back());
  yr.lo = std::min(yr.lo - y_pad, yt.front()), yr.hi = std::max(yr.hi + y_pad, yt.back());
  auto px = [&](double x) { return left + margin_left + (x - xr.lo) / (xr.hi - xr.lo) * plot_w; };
  auto py = [&](double y) {
    return top + margin_top + plot_h - (y - yr.lo) / (yr.hi - yr.lo) * plot_h;
  };

  svg << "<text x='" << left + width / 2 << "' y='" << top + 18
      << "' text-anchor='middle' font-weight='bold'>" << escapeXml(panel.title) << "</text>\n";
  svg << "<rect x='" << left + margin_left << "' y='" << top + margin_top << "' width='" << plot_w
      << "' height='" << plot_h << "' fill='none' stroke='#444'/>\n";
  const double x_step = xt.size() > 1 ? xt[1] - xt[0] : 1.0;
  const double y_step = yt.size() > 1 ? yt[1] - yt[0] : 1.0;
  for (double x : xt) {
    svg << "<line x1='" << px(x) << "' y1='" << top + margin_top << "' x2='" << px(x) << "' y2='"
        << top + margin_top + plot_h << "' stroke='#ddd'/>\n";
    svg << "<text x='" << px(x) << "' y='" << top + margin_top + plot_h + 16
        << "' text-anchor='middle' font-size='11'>" << formatTick(x, x_step) << "</text>\n";
  }
  for (double y : yt) {
    svg << "<line x1='" << left + margin_left << "' y1='" << py(y) << "' x2='"
        << left + margin_left + plot_w << "' y2='" << py(y) << "' stroke='#ddd'/>\n";
    // A log tick is 1, 2 or 5 x 10^k: its own value is its precision.
    const double value = panel.log_y ? std::pow(10.0, y) : y;
    const std::string label =
        panel.log_y ? formatTick(value, value * (1.0 - 1e-9)) : formatTick(y, y_step);
    svg << "<text x='" << left + margin_left - 6 << "' y='" << py(y) + 4
        << "' text-anchor='end' font-size='11'>" << label << "</text>\n";
  }
  svg << "<text x='" << left + margin_left + plot_w / 2 << "' y='" << top + height - 8
      << "' text-anchor='middle' font-size='12'>" << escapeXml(panel.x_label) << "</text>\n";
  svg << "<text transform='translate(" << left + 16 << "," << top + margin_top + plot_h / 2
      << ") rotate(-90)' text-anchor='middle' font-size='12'>" << escapeXml(panel.y_label)
      << "</text>\n";

  // The legend's width from its longest label (about 6.2 px per character at 11 px); in the
  // frame's top right corner, or in the margin right of the frame.
  std::size_t longest_label = 0;
  for (const PlotSeries& s : panel.series) longest_label = std::max(longest_label, s.label.size());
  const double legend_width = 30.0 + 6.2 * static_cast<double>(longest_label);
  const double legend_x = panel.legend_margin > 0.0 ? left + margin_left + plot_w + 12.0
                                                    : left + margin_left + plot_w - legend_width;
  // Every line first, then every marker, so that no line hides a marker; the markers of the
  // series drawn on top last (pass 2), and the legend with them.
  for (int pass = 0; pass < 3; ++pass) {
    for (std::size_t k = 0; k < panel.series.size(); ++k) {
      const PlotSeries& s = panel.series[k];
      const std::string colour =
          s.colour.empty() ? kPalette[k % (sizeof kPalette / sizeof *kPalette)] : s.colour;
      const std::size_t n = std::min(s.x.size(), s.y.size());
      if (pass == 0 && s.line) {
        std::string path;
        bool pen_down = false;
        for (std::size_t i = 0; i < n; ++i) {
          const double y = ty(s.y[i]);
          if (!std::isfinite(y) || !std::isfinite(s.x[i])) {
            pen_down = false;
            continue;
          }
          char buffer[64];
          std::snprintf(buffer, sizeof buffer, "%s%.2f,%.2f ", pen_down ? "L" : "M", px(s.x[i]),
                        py(y));
          path += buffer;
          pen_down = true;
        }
        svg << "<path d='" << path << "' fill='none' stroke='" << colour << "' stroke-width='1.5'"
            << (s.dashed ? " stroke-dasharray='6,4'" : "") << "/>\n";
      }
      if (pass == (s.on_top ? 2 : 1) && s.markers) {
        for (std::size_t i = 0; i < n; ++i) {
          const double y = ty(s.y[i]);
          if (!std::isfinite(y) || !std::isfinite(s.x[i])) continue;
          drawMarker(svg, s.marker, px(s.x[i]), py(y), s.marker_radius, colour);
        }
      }
      if (pass < 2) continue;
      // The legend entry: the line and the marker as drawn (a marker at least 3 px, so that a
      // small one reads).
      const double ly = top + margin_top + 14 + 16 * static_cast<double>(k);
      if (s.line)
        svg << "<line x1='" << legend_x << "' y1='" << ly - 4 << "' x2='" << legend_x + 18
            << "' y2='" << ly - 4 << "' stroke='" << colour << "' stroke-width='2'"
            << (s.dashed ? " stroke-dasharray='6,4'" : "") << "/>\n";
      if (s.markers || !s.line)
        drawMarker(svg, s.marker, legend_x + 9, ly - 4,
                   std::min(6.0, std::max(3.0, s.marker_radius)), colour);
      svg << "<text x='" << legend_x + 22 << "' y='" << ly << "' font-size='11'>"
          << escapeXml(s.label) << "</text>\n";
    }
  }
}

}  // namespace

std::vector<double> niceTicks(double lo, double hi, int target) {
  if (!(hi > lo)) return {lo};
  const double raw = (hi - lo) / std::max(1, target);
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double step = magnitude;
  for (double factor : {1.0, 2.0, 5.0, 10.0}) {
    step = factor * magnitude;
    if (step >= raw * (1.0 - 1e-9)) break;  // round-off must not skip a step
  }
  std::vector<double> ticks;
  for (double t = std::floor(lo / step) * step;; t += step) {
    ticks.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
    if (t >= hi - 1e-9 * step || ticks.size() > 100) break;
  }
  return ticks;
}

std::vector<double> logTicks(double lo_exponent, double hi_exponent, int max_ticks) {
  const int first = static_cast<int>(std::floor(lo_exponent + 1e-9));
  const int last = static_cast<int>(std::ceil(hi_exponent - 1e-9));
  for (const std::vector<double>& mantissas :
       {std::vector<double>{1, 2, 5}, std::vector<double>{1}}) {
    std::vector<double> ticks;
    for (int k = first; k <= last; ++k) {
      for (double m : mantissas) {
        const double exponent = std::log10(m) + k;
        // Keep the last tick at or below the range and the first at or above it.
        if (exponent < lo_exponent - 1e-9) {
          ticks.assign(1, m * std::pow(10.0, k));
          continue;
        }
        ticks.push_back(m * std::pow(10.0, k));
        if (exponent >= hi_exponent - 1e-9) break;
      }
      if (!ticks.empty() && std::log10(ticks.back()) >= hi_exponent - 1e-9) break;
    }
    if (static_cast<int>(ticks.size()) <= max_ticks) return ticks;
    if (mantissas.size() == 1) {
      // Decades, every k-th, so that a range of hundreds of decades keeps a readable axis.
      const std::size_t k = (ticks.size() + max_ticks - 1) / max_ticks;
      std::vector<double> thinned;
      for (std::size_t i = 0; i < ticks.size(); i += k) thinned.push_back(ticks[i]);
      if (std::log10(thinned.back()) < hi_exponent - 1e-9)
        thinned.push_back(thinned.back() * std::pow(10.0, static_cast<double>(k)));
      return thinned;
    }
  }
  return {};
}

std::string svgLinePlots(const std::vector<PlotPanel>& panels, int columns, int panel_width,
                         int panel_height) {
  columns = std::max(1, columns);
  const int rows = static_cast<int>((panels.size() + columns - 1) / columns);
  std::ostringstream svg;
  svg << "<svg xmlns='http://www.w3.org/2000/svg' width='" << columns * panel_width << "' height='"
      << std::max(1, rows) * panel_height << "' font-family='Helvetica, Arial, sans-serif'>\n"
      << "<rect width='100%' height='100%' fill='white'/>\n";
  for (std::size_t i = 0; i < panels.size(); ++i) {
    drawPanel(svg, panels[i], static_cast<double>((i % columns) * panel_width),
              static_cast<double>((i / columns) * panel_height), panel_width, panel_height);
  }
  svg << "</svg>\n";
  return svg.str();
}

}  // namespace chordfit
