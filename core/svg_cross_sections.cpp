#include "core/svg_cross_sections.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <vector>

#include "core/svg_text.h"

namespace chordfit {

namespace {

constexpr double kMarginLeft = 48.0;    // px, room for y tick labels
constexpr double kMarginBottom = 36.0;  // px, x tick labels and axis label
constexpr double kMarginTop = 24.0;     // px, panel title
constexpr double kMarginRight = 12.0;
constexpr double kFigureTitle = 30.0;   // px
constexpr double kLegendRow = 20.0;     // px per legend row
constexpr double kLegendSample = 30.0;  // px, the entry's line or marker and the gap after it
constexpr double kLegendGap = 22.0;     // px between two entries of a row
constexpr double kLegendChar = 6.2;     // px per character at 11 px, generously
constexpr double kLegendSide = 16.0;    // px kept free at each side of the legend
constexpr double kRingRim = 0.9;        // px, the stroke of a hollow ring marker

std::string number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.2f", value);
  return buffer;
}

// The stroke-dasharray attribute of a line style, with its leading space ("" when solid).
std::string dashAttribute(SvgStroke stroke) {
  switch (stroke) {
    case SvgStroke::kDashed:
      return " stroke-dasharray=\"4,3\"";
    case SvgStroke::kDotted:
      return " stroke-dasharray=\"1,2\"";
    case SvgStroke::kSolid:
      break;
  }
  return "";
}

// A marker centred at (x, y) px: a disc, a square or a hollow ring of radius (half side) r.
void drawMarker(std::ostringstream& svg, SvgSeries::Kind kind, double x, double y, double r) {
  if (kind == SvgSeries::Kind::kSquares) {
    svg << "<rect x=\"" << number(x - r) << "\" y=\"" << number(y - r) << "\" width=\""
        << number(2 * r) << "\" height=\"" << number(2 * r) << "\"/>\n";
  } else {
    svg << "<circle cx=\"" << number(x) << "\" cy=\"" << number(y) << "\" r=\"" << number(r)
        << "\"/>\n";
  }
}

// The group attributes of a marker series: a filled disc or square, or a ring (white inside,
// so that a line under it does not show through, a rim of the series' colour).
std::string markerGroup(const SvgSeries& series) {
  if (series.kind == SvgSeries::Kind::kRings)
    return "<g fill=\"white\" stroke=\"" + series.colour + "\" stroke-width=\"" + number(kRingRim) +
           "\">\n";
  return "<g fill=\"" + series.colour + "\">\n";
}

struct Bounds {
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0;
  double y0 = x0, y1 = -x0;
  void add(double x, double y) {
    x0 = std::min(x0, x);
    x1 = std::max(x1, x);
    y0 = std::min(y0, y);
    y1 = std::max(y1, y);
  }
  bool empty() const { return !(x1 >= x0 && y1 >= y0); }
};

// Tick step among 1, 2, 5, 10, 20, ... mm giving at most ~8 ticks over `range`.
double tickStep(double range) {
  for (double step : {1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0}) {
    if (range / step <= 8.0) return step;
  }
  return 200.0;
}

// Maps panel mm to figure px.
struct Transform {
  double left = 0, top = 0, scale = 1;  // px origin of the plot area, px per mm
  Bounds bounds;
  double x(double u) const { return left + (u - bounds.x0) * scale; }
  double y(double w) const { return top + (bounds.y1 - w) * scale; }
};

// Tick positions k * step within [lo, hi], at most kMaxTicks of them. Counting k rather than
// adding step to a coordinate: far from the origin a tiny step (a panel of one far point) is
// below the coordinate's rounding and u += step never advances.
std::vector<double> ticks(double lo, double hi, double step) {
  constexpr int kMaxTicks = 100;
  std::vector<double> out;
  if (!(step > 0.0) || !std::isfinite(lo) || !std::isfinite(hi)) return out;
  const double first = std::ceil(lo / step), last = std::floor(hi / step);
  if (!(last - first < kMaxTicks)) return out;
  for (double k = first; k <= last; k += 1.0) out.push_back(k * step);
  return out;
}

void drawAxes(std::ostringstream& svg, const Transform& t, const SvgFigureOptions& options) {
  const Bounds& b = t.bounds;
  const double width = (b.x1 - b.x0) * t.scale;
  const double height = (b.y1 - b.y0) * t.scale;
  const double step = tickStep(std::max(b.x1 - b.x0, b.y1 - b.y0));
  const std::vector<double> x_ticks = ticks(b.x0, b.x1, step), y_ticks = ticks(b.y0, b.y1, step);
  svg << "<g stroke=\"#e3e3e3\" stroke-width=\"0.6\">\n";
  for (const double u : x_ticks) {
    svg << "<line x1=\"" << number(t.x(u)) << "\" y1=\"" << number(t.top) << "\" x2=\""
        << number(t.x(u)) << "\" y2=\"" << number(t.top + height) << "\"/>\n";
  }
  for (const double w : y_ticks) {
    svg << "<line x1=\"" << number(t.left) << "\" y1=\"" << number(t.y(w)) << "\" x2=\""
        << number(t.left + width) << "\" y2=\"" << number(t.y(w)) << "\"/>\n";
  }
  svg << "</g>\n";
  svg << "<rect x=\"" << number(t.left) << "\" y=\"" << number(t.top) << "\" width=\""
      << number(width) << "\" height=\"" << number(height)
      << "\" fill=\"none\" stroke=\"#444\" stroke-width=\"0.8\"/>\n";
  svg << "<g font-family=\"sans-serif\" font-size=\"9\" fill=\"#333\">\n";
  for (const double u : x_ticks) {
    svg << "<text x=\"" << number(t.x(u)) << "\" y=\"" << number(t.top + height + 11)
        << "\" text-anchor=\"middle\">" << std::lround(u) << "</text>\n";
  }
  for (const double w : y_ticks) {
    svg << "<text x=\"" << number(t.left - 4) << "\" y=\"" << number(t.y(w) + 3)
        << "\" text-anchor=\"end\">" << std::lround(w) << "</text>\n";
  }
  svg << "<text x=\"" << number(t.left + 0.5 * width) << "\" y=\"" << number(t.top + height + 25)
      << "\" text-anchor=\"middle\">" << escapeXml(options.x_label) << "</text>\n";
  svg << "<text transform=\"translate(" << number(t.left - 34) << ","
      << number(t.top + 0.5 * height) << ") rotate(-90)\" text-anchor=\"middle\">"
      << escapeXml(options.y_label) << "</text>\n";
  svg << "</g>\n";
}

void drawSeries(std::ostringstream& svg, const Transform& t, const SvgSeries& series) {
  for (const Eigen::MatrixXd& part : series.parts) {
    if (part.rows() == 0) continue;
    if (series.kind == SvgSeries::Kind::kLine) {
      svg << "<polyline fill=\"none\" stroke=\"" << series.colour << "\" stroke-width=\""
          << number(series.size) << "\" stroke-linejoin=\"round\"" << dashAttribute(series.stroke)
          << " points=\"";
      for (Eigen::Index i = 0; i < part.rows(); ++i) {
        svg << (i ? " " : "") << number(t.x(part(i, 0))) << "," << number(t.y(part(i, 1)));
      }
      svg << "\"/>\n";
      continue;
    }
    svg << markerGroup(series);
    for (Eigen::Index i = 0; i < part.rows(); ++i)
      drawMarker(svg, series.kind, t.x(part(i, 0)), t.y(part(i, 1)), series.size);
    svg << "</g>\n";
  }
}

// A legend entry's sample, as its series is drawn (a marker of 2 px radius at least,
// so that a small one still reads), and its label.
void drawLegendEntry(std::ostringstream& svg, double x, double y, const SvgSeries& series) {
  if (series.kind == SvgSeries::Kind::kLine) {
    svg << "<line x1=\"" << number(x) << "\" y1=\"" << number(y) << "\" x2=\"" << number(x + 24)
        << "\" y2=\"" << number(y) << "\" stroke=\"" << series.colour << "\" stroke-width=\""
        << number(series.size) << "\"" << dashAttribute(series.stroke) << "/>\n";
  } else {
    const double r = std::max(series.kind == SvgSeries::Kind::kSquares ? 2.5 : 2.0, series.size);
    svg << markerGroup(series);
    drawMarker(svg, series.kind, x + 12, y, r);
    svg << "</g>\n";
  }
  svg << "<text x=\"" << number(x + kLegendSample) << "\" y=\"" << number(y + 4)
      << "\" font-family=\"sans-serif\" font-size=\"11\" fill=\"#222\">" << escapeXml(series.label)
      << "</text>\n";
}

// The legend's grid: `rows` rows, filled column by column, each column as wide as its widest
// entry.
struct LegendLayout {
  int rows = 0;
  std::vector<double> column_widths;
  double width() const {
    double sum = 0.0;
    for (double w : column_widths) sum += w;
    return sum + kLegendGap * std::max<double>(0.0, column_widths.size() - 1.0);
  }
};

LegendLayout legendLayout(const std::vector<const SvgSeries*>& legend, int rows) {
  LegendLayout layout;
  layout.rows = rows;
  const int n = static_cast<int>(legend.size());
  const int columns = (n + rows - 1) / rows;
  layout.column_widths.assign(columns, 0.0);
  for (int i = 0; i < n; ++i) {
    const double entry = kLegendSample + kLegendChar * static_cast<double>(legend[i]->label.size());
    layout.column_widths[i / rows] = std::max(layout.column_widths[i / rows], entry);
  }
  return layout;
}

// The fewest rows whose grid fits `available` px; with that many rows, as few columns as hold
// the entries, so the rows are as full as each other (within one entry).
LegendLayout fitLegend(const std::vector<const SvgSeries*>& legend, double available) {
  const int n = static_cast<int>(legend.size());
  if (n == 0) return {};
  for (int rows = 1; rows < n; ++rows) {
    const int columns = (n + rows - 1) / rows;
    if ((n + columns - 1) / columns != rows) continue;  // the same grid as fewer rows
    const LegendLayout layout = legendLayout(legend, rows);
    if (layout.width() <= available) return layout;
  }
  return legendLayout(legend, n);
}

}  // namespace

std::string crossSectionsSvg(const std::vector<SvgPanel>& panels, const SvgFigureOptions& options) {
  Bounds bounds;
  std::vector<const SvgSeries*> legend;
  for (const SvgPanel& panel : panels) {
    for (const SvgSeries& series : panel.series) {
      for (const Eigen::MatrixXd& part : series.parts) {
        for (Eigen::Index i = 0; i < part.rows(); ++i) bounds.add(part(i, 0), part(i, 1));
      }
      if (series.label.empty()) continue;
      const bool seen = std::any_of(legend.begin(), legend.end(),
                                    [&](const SvgSeries* s) { return s->label == series.label; });
      if (!seen) legend.push_back(&series);
    }
  }
  if (bounds.empty()) bounds = Bounds{-1.0, 1.0, -1.0, 1.0};
  bounds.x0 -= options.padding_mm;
  bounds.x1 += options.padding_mm;
  bounds.y0 -= options.padding_mm;
  bounds.y1 += options.padding_mm;

  const int columns = std::max(1, options.columns);
  const int rows = std::max(1, (static_cast<int>(panels.size()) + columns - 1) / columns);
  const double plot_width = options.panel_width_px - kMarginLeft - kMarginRight;
  const double scale = plot_width / (bounds.x1 - bounds.x0);
  const double panel_height = kMarginTop + (bounds.y1 - bounds.y0) * scale + kMarginBottom;
  const double width = columns * options.panel_width_px;
  const LegendLayout legend_layout = fitLegend(legend, width - 2.0 * kLegendSide);
  const double header = kFigureTitle + legend_layout.rows * kLegendRow + 6.0;
  const double height = header + rows * panel_height;

  std::ostringstream svg;
  svg << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << number(width) << "\" height=\""
      << number(height) << "\" viewBox=\"0 0 " << number(width) << " " << number(height) << "\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << "<text x=\"" << number(0.5 * width)
      << "\" y=\"20\" font-family=\"sans-serif\" font-size=\"15\" text-anchor=\"middle\" "
         "fill=\"#111\">"
      << escapeXml(options.title) << "</text>\n";
  // The legend centred under the title (at the left edge when wider than the figure).
  std::vector<double> column_x(legend_layout.column_widths.size());
  double x = std::max(kLegendSide, 0.5 * (width - legend_layout.width()));
  for (std::size_t c = 0; c < column_x.size(); ++c) {
    column_x[c] = x;
    x += legend_layout.column_widths[c] + kLegendGap;
  }
  for (std::size_t i = 0; i < legend.size(); ++i) {
    const std::size_t rows = static_cast<std::size_t>(legend_layout.rows);
    const double y = kFigureTitle + static_cast<double>(i % rows) * kLegendRow + 6.0;
    drawLegendEntry(svg, column_x[i / rows], y, *legend[i]);
  }
  for (std::size_t p = 0; p < panels.size(); ++p) {
    const double left = (p % columns) * options.panel_width_px;
    const double top = header + (p / columns) * panel_height;
    Transform t;
    t.left = left + kMarginLeft;
    t.top = top + kMarginTop;
    t.scale = scale;
    t.bounds = bounds;
    svg << "<text x=\"" << number(t.left + 0.5 * plot_width) << "\" y=\"" << number(top + 16)
        << "\" font-family=\"sans-serif\" font-size=\"12\" text-anchor=\"middle\" fill=\"#111\">"
        << escapeXml(panels[p].title) << "</text>\n";
    drawAxes(svg, t, options);
    for (const SvgSeries& series : panels[p].series) drawSeries(svg, t, series);
  }
  svg << "</svg>\n";
  return svg.str();
}

}  // namespace chordfit
