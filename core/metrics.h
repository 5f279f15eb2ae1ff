// Metrics of a closed valve (DESIGN §6, the paper's Table 1):
//   deviation  distance from every tracing point to the closed mesh surface (exact
//              point-to-triangle, CGAL AABB tree): min, median, max, mean, SD in mm;
//   area       valve surface area, mm^2;
//   prolapse   leaflet points more than 2 mm above the closed annulus toward the atrium,
//              localised to Carpentier segments; computed for the mesh and, independently,
//              for the tracings. "Prolapse reconstructed" = same segment set (none <=> none).
#pragma once

#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/annulus_plane.h"
#include "core/carpentier.h"
#include "core/case_data.h"
#include "core/orifice_coverage.h"

namespace chordfit {

struct DeviationStats {
  int count = 0;  // number of tracing points; the statistics are NaN when 0
  double min = 0, median = 0, max = 0, mean = 0, sd = 0;  // mm; sd uses n - 1
};

// Distances from each row of `points` to the triangle mesh (V, F). #points values, mm.
Eigen::VectorXd pointToSurfaceDistances(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                        const Eigen::MatrixXd& points);
// Distances from each point to the faces of its own leaflet: point i is measured against the
// faces f with face_leaflet(f) == point_leaflet(i) (faceLeaflets, the labelling the tracing
// sampler uses), and against the whole mesh when its label is -1 or no face carries it.
// A tracing reader names the leaflet of every polyline, so a point of the posterior leaflet
// must not be explained by an anterior bulge that happens to pass close to it.
//   face_leaflet  #F,  point_leaflet  #points.  Returns #points values, mm; each is >= the
//   pointToSurfaceDistances value.
Eigen::VectorXd pointToOwnLeafletDistances(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                           const Eigen::VectorXi& face_leaflet,
                                           const Eigen::MatrixXd& points,
                                           const Eigen::VectorXi& point_leaflet);
DeviationStats summarizeDeviation(const Eigen::VectorXd& distances);

// Median of `values` (the mean of the middle two for an even count); NaN when empty.
double median(std::vector<double> values);

// Sum of triangle areas, mm^2.
double surfaceArea(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);

// All tracing points stacked (#P by 3) and each point's leaflet (-1 when unlabelled).
Eigen::MatrixXd stackTracingPoints(const std::vector<Tracing>& tracings,
                                   Eigen::VectorXi* leaflets = nullptr);

// Height (mm) of each point above the closed annulus toward the atrium. The reference is the
// clinical echo one (Levine et al., Circulation 1989;80:589): in the long-axis plane through
// the annulus centre, n_AP and the point, the straight line joining the two annular hinge
// points; a plain least-squares plane would call every saddle horn a prolapse.
// `frame` is the closed annulus frame, `ring` the closed ring positions (#ring by 3).
Eigen::VectorXd heightAboveAnnulus(const AnnulusFrame& frame, const Eigen::MatrixXd& ring,
                                   const Eigen::MatrixXd& points);

struct ProlapseOptions {
  double threshold_mm = 2.0;  // clinical criterion: > 2 mm above the annulus
  int min_points = 1;         // points above threshold a segment needs to count
};

struct ProlapseResult {
  std::vector<std::string> segments;  // sorted segment names, e.g. {"P2"}; empty when none
  double max_height_mm = 0.0;         // highest point above the annulus (may be negative)
  // Highest point of each segment that has points, by segment name (how far each segment is
  // from the threshold).
  std::map<std::string, double> segment_max_height_mm;
  Eigen::VectorXd heights;  // per input point
};

// Closed-state geometry shared by the prolapse computations.
struct ClosedAnnulus {
  AnnulusFrame frame;
  Eigen::MatrixXd ring;  // closed ring positions
  SegmentMap segments;
};
ClosedAnnulus closedAnnulus(const ValveCase& valve_case);

// Prolapse of `points` (closed state), each counted in its Carpentier segment
// `segment_ids(i)` (segmentOf ids; -1 = none).
ProlapseResult prolapseOfPoints(const ClosedAnnulus& annulus, const Eigen::MatrixXd& points,
                                const Eigen::VectorXi& segment_ids, const ProlapseOptions& options);
// Same, localising each point by its closed position and leaflet label (-1 = decide by
// angle): what is known of a tracing point (closedSegmentOf: segments as strips from the
// annulus to the coaptation line).
ProlapseResult prolapseOfLabelledPoints(const ClosedAnnulus& annulus, const Eigen::MatrixXd& points,
                                        const Eigen::VectorXi& leaflets,
                                        const ProlapseOptions& options);

// Segment id of every mesh vertex from its OPEN-state position (open annulus frame and ring).
// A closed leaflet folds and its free edge crosses toward the other side of the centre, so
// the closed position's angle would assign coaptation tissue to the wrong scallop; the
// open position is where the vertex anatomically belongs.
Eigen::VectorXi openStateSegments(const ValveMesh& mesh);

// Mesh: every non-annulus vertex of the closed mesh (same topology as the case mesh), each
// in the segment of its open-state position (openStateSegments).
ProlapseResult prolapseOfMesh(const ValveCase& valve_case, const Eigen::MatrixXd& closed_V,
                              const ProlapseOptions& options = {});
// Tracings: every tracing point; two points above threshold per segment so that a lone noisy
// point does not make a prolapse.
ProlapseResult prolapseOfTracings(const ValveCase& valve_case,
                                  const ProlapseOptions& options = {2.0, 2});

// The closed mesh as the tracings see it: cut by each distinct tracing plane, every section
// resampled at `spacing_mm` and localised like a tracing point (closed position and the
// leaflet of the cut triangles), same options as the tracings. This compares like with like:
// the paper judges prolapse in the image planes, and a flap leaning over the valve centre
// shows in the same segments in both.
ProlapseResult prolapseOfSections(const ValveCase& valve_case, const ClosedAnnulus& annulus,
                                  const Eigen::MatrixXd& closed_V, double spacing_mm = 0.5,
                                  const ProlapseOptions& options = {2.0, 2});

// Segments prolapsing in `tracings` but not in `sections` (sorted, as the results are): a
// prolapse the closed mesh does not make where the tracings show one.
std::vector<std::string> prolapseMissing(const ProlapseResult& tracings,
                                         const ProlapseResult& sections);
// The same for a closed mesh of the case: its sections against the case's tracings (empty
// without tracings).
std::vector<std::string> prolapseMissingInClosure(const ValveCase& valve_case,
                                                  const Eigen::MatrixXd& closed_V);

struct ValveMetrics {
  DeviationStats deviation;
  double area_mm2 = 0.0;
  ProlapseResult mesh_prolapse;
  ProlapseResult tracing_prolapse;
  ProlapseResult section_prolapse;  // prolapseOfSections; meaningful only with tracings
  bool has_tracings = false;
  // Table 1's "Prolapse reconstructed": section_prolapse.segments == tracing_prolapse.segments,
  // like with like (both read in the tracing planes, localised the same way). Meaningful only
  // with tracings.
  bool prolapse_reconstructed = false;
  // The tissue judgement: mesh_prolapse.segments (every vertex, open-state localisation) ==
  // tracing_prolapse.segments. A diagnostic: the planes may miss the highest tissue or cut a
  // neighbouring segment's bulge above the criterion, so the truth itself can fail it.
  bool tissue_prolapse_reconstructed = false;
  // Is the valve closed: the leaflets' projection onto the closed annulus plane against the
  // orifice the closed annulus vertices of the mesh enclose (orifice_coverage.h).
  OrificeCoverage orifice;
  // Pairs of non-adjacent triangles that intersect (CGAL, cgal_backend.h): the leaflets passing
  // through each other or themselves, which contact should prevent (0 expected).
  int self_intersections = 0;
  Eigen::VectorXd tracing_distances;  // per stacked tracing point
};

// All metrics of a closed mesh `closed_V` (topology = valve_case.mesh.F).
ValveMetrics computeMetrics(const ValveCase& valve_case, const Eigen::MatrixXd& closed_V);

// The paper's Table 1 as Markdown: header, separator, and one row per labelled result.
// first_column names what the rows are (a case, or the cord sets closed on one case). The
// last column says whether the closed mesh's planes prolapse where the tracings do, and
// where: "Yes (P2)", "Yes (none)", "No (mesh P1, P2; tracings P2)".
std::string table1Header(const std::string& first_column = "Case");
// "A2, P2", or "none" for no segment.
std::string joinSegments(const std::vector<std::string>& segments);
std::string table1Row(const std::string& label, const ValveMetrics& metrics);

}  // namespace chordfit
