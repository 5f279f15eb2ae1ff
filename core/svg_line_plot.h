// Minimal SVG line plots (no dependency): one or more panels, each with axes, "nice" ticks
// (1-2-5 steps), labelled series and a legend. Used for convergence plots and sweeps; the
// output opens in any browser and in Inkscape.
#pragma once

#include <string>
#include <vector>

namespace chordfit {

struct PlotSeries {
  std::string label;
  std::vector<double> x;
  std::vector<double> y;  // NaN values break the line
  bool markers = false;   // draw a small circle at each point
  bool line = true;
};

struct PlotPanel {
  std::string title;
  std::string x_label;
  std::string y_label;
  std::vector<PlotSeries> series;
  bool log_y = false;  // log10 axis; non-positive values are skipped
};

// An SVG document with the panels laid out in `columns` columns, each panel
// panel_width x panel_height pixels.
std::string svgLinePlots(const std::vector<PlotPanel>& panels, int columns = 1,
                         int panel_width = 560, int panel_height = 360);

// Tick positions covering [lo, hi] with about `target` steps of 1, 2 or 5 x 10^k.
std::vector<double> niceTicks(double lo, double hi, int target = 6);

}  // namespace chordfit
