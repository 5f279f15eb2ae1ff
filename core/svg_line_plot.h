// Minimal SVG line plots (no dependency): one or more panels, each with axes, "nice" ticks
// (1-2-5 steps), labelled series and a legend. Used for convergence plots and sweeps; the
// output opens in any browser and in Inkscape.
#pragma once

#include <string>
#include <vector>

namespace chordfit {

enum class PlotMarker { kCircle, kSquare, kDiamond, kTriangleUp, kTriangleDown };

struct PlotSeries {
  std::string label;
  std::vector<double> x;
  std::vector<double> y;  // NaN values break the line
  bool markers = false;   // draw a marker at each point
  bool line = true;
  bool dashed = false;      // a dashed line: tells apart a series drawn over another
  std::string colour = "";  // "" : the palette's colour of the series' place in its panel
  PlotMarker marker = PlotMarker::kCircle;
  // Radius of the marker's circumcircle, px. Above 2.5 px a marker gets a white rim, which
  // keeps it apart from a line or marker under it.
  double marker_radius = 2.0;
  // Markers drawn over those of every other series (its legend entry keeps its place): a few
  // key points among many small ones, which would otherwise cover them.
  bool on_top = false;
};

struct PlotPanel {
  std::string title;
  std::string x_label;
  std::string y_label;
  std::vector<PlotSeries> series;
  bool log_y = false;  // log10 axis; non-positive values are skipped
  // px kept right of the frame for the legend, which then stands there instead of in the
  // frame's top right corner (where it may cover data); 0: in the corner.
  double legend_margin = 0.0;
};

// An SVG document with the panels laid out in `columns` columns, each panel
// panel_width x panel_height pixels.
std::string svgLinePlots(const std::vector<PlotPanel>& panels, int columns = 1,
                         int panel_width = 560, int panel_height = 360);

// Tick positions covering [lo, hi] with about `target` steps of 1, 2 or 5 x 10^k: the first
// at or below lo, the last at or above hi, so no point lies on the frame beyond a tick.
std::vector<double> niceTicks(double lo, double hi, int target = 6);

// Tick values (not exponents) for a log axis over [10^lo_exponent, 10^hi_exponent]: 1, 2, 5
// x 10^k, or the decades alone when those would be more than `max_ticks` (every k-th decade
// when even those would be); the first at or below the range, the last at or above it.
std::vector<double> logTicks(double lo_exponent, double hi_exponent, int max_ticks = 9);

}  // namespace chordfit
