// The closed valve seen from the atrium, the surgeon's view (anterior leaflet up, the
// anterolateral commissure on the viewer's left, annulus_plane.h): where a closed valve
// leaves its orifice open. Every leaflet triangle is projected onto the closed annulus plane
// and drawn over the orifice, which is filled red; triangles are drawn from the lowest to the
// highest (signed distance toward the atrium), so the picture shows the atrial surface, and
// each is lighter the higher it lies above the annulus as the prolapse measure has it (the
// hinge line of heightAboveAnnulus, metrics.h). Each triangle is drawn grown by the tissue radius
// of the orifice measure (a round-joined outline of twice that width: the projection of the
// triangle swept by a ball of that radius), so the red left visible is what
// orifice_coverage.h counts as open, up to its 0.25 mm sampling. The height scale runs from
// -12 mm to the highest tissue rounded up to an even mm (4 mm at least, 12 at most), so a
// prolapsing flap stands out from the annulus' saddle horns; enfaceFiguresSvg draws several
// closures on the highest of their scales instead.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/case_data.h"
#include "core/metrics.h"

namespace chordfit {

struct EnfaceFigureOptions {
  std::string title;
  double tissue_radius_mm = 0.0;  // OrificeCoverage::tissue_radius_mm of the measure shown
  double pixels_per_mm = 12.0;
  std::string scale_note = "";  // beside the height scale, "" for none
};

// closed_V  #V by 3 closed positions of valve_case.mesh (its annulus ring included)
std::string enfaceFigureSvg(const ValveCase& valve_case, const Eigen::MatrixXd& closed_V,
                            const EnfaceFigureOptions& options);

// The same, titled "<subject>: closed valve from the atrium, orifice N % covered (...);
// prolapse (tissue): P2" (or "no prolapse") from the closure's metrics, and drawn with the
// tissue radius of its orifice measure.
std::string enfaceFigureSvg(const ValveCase& valve_case, const Eigen::MatrixXd& closed_V,
                            const std::string& subject, const ValveMetrics& metrics);

// One closure of several drawn alike (enfaceFiguresSvg).
struct EnfaceClosure {
  Eigen::MatrixXd closed_V;  // #V by 3 closed positions of the case's mesh
  std::string subject;       // the title's start, as enfaceFigureSvg's
  ValveMetrics metrics;      // the closure's metrics (the title, the tissue radius)
};

// Several closures of one case (compare: one per cord set), titled as enfaceFigureSvg's, on one
// height scale and at one size: the scale's top is the highest of the closures' own tops, the
// frame holds every closure's ring and the width the widest title, so that one shade means one
// height in every figure and the figures line up side by side. Each says so beside its scale.
std::vector<std::string> enfaceFiguresSvg(const ValveCase& valve_case,
                                          const std::vector<EnfaceClosure>& closures);

}  // namespace chordfit
