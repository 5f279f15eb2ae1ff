// Plausibility of a case's coordinates. The valve mesh must be the size of a mitral valve in
// millimetres, and every other point of the case (closed annulus, tracings, PM tips, a closed
// mesh to measure) within reach of it. Finite but absurd coordinates pass every other check
// and then break the computation: a tracing point at 1e10 mm made a figure's axis loop without
// end, a mesh scaled by 1e6 (metres taken for micrometres) made the section resampling
// allocate until the machine ran out of memory, and a mesh in metres has an area of 0 mm².
#pragma once

#include <string>
#include <utility>

#include <Eigen/Core>

#include "core/cordset.h"
#include "core/curve_io.h"
#include "core/diagnostics.h"
#include "core/valve_mesh.h"

namespace chordfit {

// Span (bounding-box diagonal) of an open mitral valve mesh, mm: adult valves span ~30-60 mm;
// the limits leave room for paediatric and dilated valves and for test geometries, and catch
// metres (~0.05) and micrometres (~5e4).
constexpr double kMinValveSpanMm = 2.0;
constexpr double kMaxValveSpanMm = 500.0;

// The bounding-box diagonal of V (0 for fewer than one vertex).
double boundingDiagonal(const Eigen::MatrixXd& V);

// Error (file, "vertices") unless the mesh's span lies within the limits above; a span too
// large also names the vertex farthest from the vertices' median (an outlier, if one).
bool checkValveSpan(const Eigen::MatrixXd& V, const std::string& file, Diagnostics& diagnostics);

// Farthest a point of the case may lie from the mesh's bounding box: the larger of 50 mm and
// the mesh's span (PM tips sit ~20-30 mm below the annulus; tracings and the closed annulus
// within millimetres of the leaflets).
double valveReachMm(const Eigen::MatrixXd& mesh_V);

// Error (file, "<where>[k]") for each row of `points` farther than valveReachMm from the
// bounding box of mesh_V (at most a few lines: the first offenders and a count).
bool checkPointsNearValve(const Eigen::MatrixXd& mesh_V, const Eigen::MatrixXd& points,
                          const std::string& file, const std::string& where,
                          Diagnostics& diagnostics);

// The same for the points of a curve file (named `file` in messages), each reported where it
// stands in the file (Curve::point_wheres: "line 4" of a .csv), the count of others at the file.
bool checkCurveNearValve(const Eigen::MatrixXd& mesh_V, const Curve& curve, const std::string& file,
                         Diagnostics& diagnostics);

// The closed annulus against the open ring it moves (row k of `closed` is where ring vertex k
// goes): the same winding (Newell normals of the two polygons at less than 90 degrees), a
// perimeter within 0.5-4 times the ring's, no side under a tenth of the ring's mean side, no
// side crossing another (seen along the ring's normal: two points swapped), and the same start (no
// cyclic shift by an eighth of the ring or more, each polygon about its centre, fits the ring
// better). Errors name (file, "points"). A reversed, shifted or half-turned order, or a collapsed
// annulus, passed every other check and then made the closure diverge (exit 3) or pull the ring
// across.
bool checkClosedAnnulus(const Eigen::MatrixXd& open_ring, const Eigen::MatrixXd& closed,
                        const std::string& file, Diagnostics& diagnostics,
                        const std::vector<std::string>& point_wheres = {});

// Two PM tips closer than this give every cord one origin: refused wherever tips are read.
constexpr double kMinPmTipSeparationMm = 1.0;
// The first pair (earlier, later) of tips whose open positions lie closer than
// kMinPmTipSeparationMm, in the order the later tip comes; {-1, -1} when none.
std::pair<int, int> tipsTooClose(const std::vector<PmTip>& tips);

// The same for PM tips: errors (file, "tips[t].position" or "tips[t].closed_position").
bool checkTipsNearValve(const Eigen::MatrixXd& mesh_V, const std::vector<PmTip>& tips,
                        const std::string& file, Diagnostics& diagnostics);

// Each tip's open position below the open annulus plane (the side the leaflets hang into):
// errors (file, "tips[t].position"). A tip above it (edit-cords --move-tip with the wrong
// sign, a file in another frame) was accepted and pulled the cords up through the valve.
bool checkTipsBelowAnnulus(const ValveMesh& mesh, const std::vector<PmTip>& tips,
                           const std::string& file, Diagnostics& diagnostics);

// Both: what every reader of a case's or a cord set's tips checks.
bool checkTipPlacement(const ValveMesh& mesh, const std::vector<PmTip>& tips,
                       const std::string& file, Diagnostics& diagnostics);

}  // namespace chordfit
