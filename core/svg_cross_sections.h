// A hand-written SVG figure of 2D panels in millimetres: one panel per image plane, each with
// polylines and markers (cross-sections of meshes, tracing points, annulus points), shared
// axes with ticks in mm, equal aspect, and one legend for the figure. Plain text output; no
// plotting library.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace chordfit {

// How a line is stroked: solid, dashed (4 px dashes, 3 px gaps) or dotted (1 px dots, 2 px
// gaps): a dotted line stays distinct from a dashed one where the two cross.
enum class SvgStroke { kSolid, kDashed, kDotted };

struct SvgSeries {
  // kRings: hollow circles (a white centre, a coloured rim), which stay visible on a line of
  // any colour drawn under them, their own included.
  enum class Kind { kLine, kDots, kSquares, kRings };
  Kind kind = Kind::kLine;
  // Polylines (kLine) or point sets (markers), each #P by 2 in panel coordinates (mm):
  // column 0 horizontal, column 1 vertical (up).
  std::vector<Eigen::MatrixXd> parts;
  std::string colour = "#000000";
  double size = 1.5;  // stroke width (lines) or marker radius / half side (markers), px
  SvgStroke stroke = SvgStroke::kSolid;  // lines only
  std::string label;  // legend text; series with equal labels share one legend entry
};

struct SvgPanel {
  std::string title;
  std::vector<SvgSeries> series;
};

struct SvgFigureOptions {
  std::string title;
  std::string x_label = "mm";
  std::string y_label = "mm";
  int columns = 3;
  double panel_width_px = 360.0;  // panel height follows from the data aspect ratio
  double padding_mm = 2.0;        // around the common data bounds
};

// The whole figure as an SVG document. All panels share the same bounds (the union of all
// data, padded) and scale, so shapes compare across planes. The legend under the title draws
// each entry as its series is drawn, in as few rows as fit the figure's width, its entries
// spread evenly over the rows (filled column by column) so that none is left alone on a row
// it could share.
std::string crossSectionsSvg(const std::vector<SvgPanel>& panels, const SvgFigureOptions& options);

}  // namespace chordfit
