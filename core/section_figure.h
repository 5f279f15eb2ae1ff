// Closed valves against their tracings, one panel per image plane (the paper's Fig. 5a and
// Fig. 6 view): what an echo reader looks at to judge a simulation. Each panel shows the
// tracing points of its plane, the section of every given mesh state by the plane, the closed
// annulus points (the hinges) and the prolapse threshold of metrics.h: the straight line
// joining the two hinges raised by 2 mm (Levine et al. 1989), so a reader sees directly which
// part of a section counts as prolapse.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/case_data.h"
#include "core/svg_cross_sections.h"
#include "core/tracing_sampler.h"

namespace chordfit {

// P (#P by 3) in the plane's coordinates (#P by 2): (u . (p - origin), w . (p - origin)).
Eigen::MatrixXd projectToPlane(const ImagePlane& plane, const Eigen::MatrixXd& P);

// Where the closed polyline `ring` (#ring by 3) crosses the plane, projected (#hits by 2).
Eigen::MatrixXd ringCrossings(const ImagePlane& plane, const Eigen::MatrixXd& ring);

// One mesh state drawn in every panel: its section by the plane.
struct SectionLayer {
  std::string label;   // legend text
  Eigen::MatrixXd V;   // #V by 3 positions; topology F and leaflets of the figure's mesh
  std::string colour;  // empty: one colour per leaflet ("<label>, <leaflet name>" in the legend)
  bool dashed = false;
  double width = 2.0;  // stroke width, px
};

struct SectionFigureOptions {
  std::string title;
  bool open_annulus = false;       // also mark the open ring's crossings
  bool prolapse_threshold = true;  // the hinge line + 2 mm (needs two closed ring crossings)
  double threshold_mm = 2.0;       // ProlapseOptions::threshold_mm
  std::string tracing_label = "tracing points";
};

// The figure: one panel per plane (titled with its angle from the AP axis), each with the
// layers in order, the annulus points (orange squares), the threshold line (thin, grey,
// dotted: a dashed layer stays distinct from it) and the tracing points of the plane (tracings
// whose normal matches the plane's to 1e-9) on top, as hollow rings, distinct from any layer's
// line whatever its colour.
//   mesh         topology F, vertex leaflet labels and names, and the open ring
//                (mesh.V(annulus)) of the layers
//   closed_ring  #ring by 3 closed annulus positions (valve_case.annulus_closed)
std::string sectionFigureSvg(const ValveMesh& mesh, const Eigen::MatrixXd& closed_ring,
                             const std::vector<Tracing>& tracings,
                             const std::vector<ImagePlane>& planes,
                             const std::vector<SectionLayer>& layers,
                             const SectionFigureOptions& options);

// sectionFigureSvg of a case: its mesh, closed ring, tracings and tracing
// planes (tracingPlanes of the closed annulus frame). Empty string when the case has no
// tracings.
std::string caseSectionFigureSvg(const ValveCase& valve_case,
                                 const std::vector<SectionLayer>& layers,
                                 const SectionFigureOptions& options);

}  // namespace chordfit
