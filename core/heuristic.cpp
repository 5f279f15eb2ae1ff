#include "core/heuristic.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/carpentier.h"
#include "core/counted.h"
#include "core/graph_distance.h"
#include "core/mesh_topology.h"

namespace chordfit {

namespace {

constexpr double kTwoPi = 6.283185307179586;

std::vector<int> ringVector(const ValveMesh& mesh) {
  return std::vector<int>(mesh.annulus.data(), mesh.annulus.data() + mesh.annulus.size());
}

double meanEdgeLength(const ValveMesh& mesh) {
  double sum = 0.0;
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      sum += (mesh.V.row(mesh.F(f, k)) - mesh.V.row(mesh.F(f, (k + 1) % 3))).norm();
    }
  }
  return mesh.F.rows() > 0 ? sum / (3.0 * static_cast<double>(mesh.F.rows())) : 1.0;
}

// Primary cords: n = round(L / spacing) points evenly spaced in arc length along a free-edge
// loop, starting at its most anterior vertex so the layout is symmetric about A2/P2.
void placePrimaries(const ValveMesh& mesh, const AnnulusFrame& frame, const std::vector<int>& loop,
                    const Eigen::VectorXd& annulus_distance, const HeuristicOptions& options,
                    std::vector<CordAttachment>& out, std::set<int>& used) {
  const int n = static_cast<int>(loop.size());
  if (n < 2) return;
  int start = 0;
  for (int i = 1; i < n; ++i) {
    if (frame.a.dot(mesh.V.row(loop[i]).transpose()) >
        frame.a.dot(mesh.V.row(loop[start]).transpose())) {
      start = i;
    }
  }
  std::vector<double> arc(n + 1, 0.0);  // arc length from `start` to loop[(start + i) % n]
  for (int i = 0; i < n; ++i) {
    arc[i + 1] =
        arc[i] + (mesh.V.row(loop[(start + i) % n]) - mesh.V.row(loop[(start + i + 1) % n])).norm();
  }
  const double length = arc[n];
  const int count =
      std::max(1, spacedCordCount(length, options.primary_spacing_mm, "primary cord spacing"));
  for (int k = 0; k < count; ++k) {
    const double target = length * k / count;
    const auto it = std::lower_bound(arc.begin(), arc.end(), target);
    int i = static_cast<int>(it - arc.begin());
    if (i > 0 && (i == n + 1 || target - arc[i - 1] < arc[i] - target)) --i;
    const int vertex = loop[(start + i) % n];
    if (annulus_distance(vertex) < options.min_annulus_distance_mm) continue;
    if (used.insert(vertex).second) out.push_back({vertex, CordKind::kPrimary, std::nullopt});
  }
}

// Secondary cords: the belly line is the set of vertices about secondary_depth from the
// free edge; split it into equal angular bins around the annulus centre and take, per bin,
// the vertex nearest the line.
void placeSecondaries(const ValveMesh& mesh, const AnnulusFrame& frame,
                      const Eigen::VectorXd& annulus_distance,
                      const Eigen::VectorXd& free_edge_distance, const HeuristicOptions& options,
                      std::vector<CordAttachment>& out, std::set<int>& used) {
  const double tolerance = 0.75 * meanEdgeLength(mesh);
  std::vector<int> candidates;
  double radius_sum = 0.0;
  for (Eigen::Index v = 0; v < mesh.V.rows(); ++v) {
    if (annulus_distance(v) < options.min_annulus_distance_mm) continue;
    if (std::abs(free_edge_distance(v) - options.secondary_depth_mm) > tolerance) continue;
    if (used.count(static_cast<int>(v))) continue;
    candidates.push_back(static_cast<int>(v));
    const Eigen::Vector3d d = mesh.V.row(v).transpose() - frame.plane.centre;
    radius_sum += (d - frame.plane.normal.dot(d) * frame.plane.normal).norm();
  }
  if (candidates.empty()) return;
  const double belly_radius = radius_sum / static_cast<double>(candidates.size());
  const int bins = std::max(1, spacedCordCount(kTwoPi * belly_radius, options.secondary_spacing_mm,
                                               "secondary cord spacing"));
  std::vector<int> best(bins, -1);
  std::vector<double> best_score(bins, 0.0);
  for (int v : candidates) {
    const double theta = annulusAngle(frame, mesh.V.row(v).transpose());
    const int bin = std::min(bins - 1, static_cast<int>((theta + M_PI) / kTwoPi * bins));
    const double score = std::abs(free_edge_distance(v) - options.secondary_depth_mm);
    if (best[bin] < 0 || score < best_score[bin]) {
      best[bin] = v;
      best_score[bin] = score;
    }
  }
  for (int v : best) {
    if (v >= 0 && used.insert(v).second) out.push_back({v, CordKind::kSecondary, std::nullopt});
  }
}

std::vector<int> nearestTipInPlane(const ValveMesh& mesh, const Plane& plane,
                                   const std::vector<PmTip>& tips,
                                   const std::vector<int>& vertices) {
  auto in_plane = [&](const Eigen::Vector3d& p) -> Eigen::Vector3d {
    return p - plane.signedDistance(p) * plane.normal;
  };
  std::vector<int> subset;
  for (int v : vertices) {
    const Eigen::Vector3d p = in_plane(mesh.V.row(v).transpose());
    int best = 0;
    for (std::size_t t = 1; t < tips.size(); ++t) {
      if ((in_plane(tips[t].position) - p).norm() < (in_plane(tips[best].position) - p).norm()) {
        best = static_cast<int>(t);
      }
    }
    subset.push_back(best);
  }
  return subset;
}

}  // namespace

int spacedCordCount(double length, double spacing, const char* what) {
  // No valve mesh has a million vertices on a line; the bound keeps the cast exact.
  constexpr double kMaxCount = 1e6;
  std::ostringstream problem;
  problem << "cord placement: " << what << ": ";
  const double count = std::round(length / spacing);
  if (!(spacing >= kMinCordSpacingMm) || !std::isfinite(spacing))
    problem << "must be at least " << kMinCordSpacingMm << " mm, got " << spacing;
  else if (!(count >= 0.0 && count <= kMaxCount))
    problem << length << " mm at " << spacing << " mm gives no sensible cord count";
  else
    return static_cast<int>(count);
  throw std::invalid_argument(problem.str());
}

std::vector<std::vector<int>> freeEdgeLoops(const ValveMesh& mesh) {
  const std::set<int> ring(mesh.annulus.data(), mesh.annulus.data() + mesh.annulus.size());
  std::vector<std::vector<int>> loops;
  for (std::vector<int>& loop : boundaryLoops(mesh.F)) {
    const bool on_ring =
        std::all_of(loop.begin(), loop.end(), [&](int v) { return ring.count(v); });
    if (!on_ring) loops.push_back(std::move(loop));
  }
  return loops;
}

std::vector<CordAttachment> placeCordAttachments(const ValveMesh& mesh,
                                                 const HeuristicOptions& options) {
  const AnnulusFrame frame = openAnnulusFrame(mesh);
  const std::vector<std::vector<int>> loops = freeEdgeLoops(mesh);
  std::vector<int> free_edge;
  for (const auto& loop : loops) free_edge.insert(free_edge.end(), loop.begin(), loop.end());
  const Eigen::VectorXd annulus_distance = edgeGraphDistance(mesh.V, mesh.F, ringVector(mesh));
  const Eigen::VectorXd free_edge_distance = edgeGraphDistance(mesh.V, mesh.F, free_edge);

  std::vector<CordAttachment> attachments;
  std::set<int> used;
  for (const auto& loop : loops) {
    placePrimaries(mesh, frame, loop, annulus_distance, options, attachments, used);
  }
  placeSecondaries(mesh, frame, annulus_distance, free_edge_distance, options, attachments, used);
  return attachments;
}

std::vector<int> splitBySide(const ValveMesh& mesh, const AnnulusFrame& frame,
                             const std::vector<int>& vertices) {
  std::vector<int> subset;
  subset.reserve(vertices.size());
  for (int v : vertices) {
    const double lateral = frame.l.dot(mesh.V.row(v).transpose() - frame.plane.centre);
    subset.push_back(lateral >= 0.0 ? 0 : 1);
  }
  return subset;
}

Eigen::Vector3d heuristicTipPosition(const Plane& annulus_plane,
                                     const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) centroid += p;
  centroid /= static_cast<double>(std::max<std::size_t>(1, points.size()));
  const double d = std::abs(annulus_plane.signedDistance(centroid));
  return centroid - d * annulus_plane.normal;  // away from the atrium (normal points to it)
}

double heuristicRestLength(const Eigen::Vector3d& p, const Plane& annulus_plane,
                           const Eigen::Vector3d& tip) {
  return std::abs(annulus_plane.signedDistance(p)) + (p - tip).norm();
}

namespace {

// Whether heuristicCordSet takes its tips from the case's cords (else it places the cords).
bool usesCaseCords(const ValveCase& valve_case) {
  return valve_case.cords && !valve_case.cords->cords.empty();
}

}  // namespace

std::string pmTipsCountProblem(const ValveCase& valve_case) {
  if (!valve_case.tips || !usesCaseCords(valve_case)) return "";
  const std::size_t given = valve_case.tips->size();
  const std::vector<PmTip>& paired = valve_case.cords->tips;
  if (given == paired.size()) return "";
  std::string names;
  for (const PmTip& tip : paired) names += (names.empty() ? "" : ", ") + tip.name;
  return counted(given, "PM tip") + " for the cord set's " + counted(paired.size(), "tip") + " (" +
         names +
         "): with the case's cords the heuristic takes each tip's position from the PM tip "
         "in the same place in the list, so the counts must match";
}

CordSet heuristicCordSet(const ValveCase& valve_case, const HeuristicOptions& options) {
  const ValveMesh& mesh = valve_case.mesh;
  const AnnulusFrame frame = openAnnulusFrame(mesh);

  std::vector<CordAttachment> attachments;
  std::vector<int> subset;
  std::vector<std::string> tip_names{"anterolateral", "posteromedial"};
  std::vector<double> compliance;
  if (usesCaseCords(valve_case)) {
    tip_names.clear();
    for (const PmTip& tip : valve_case.cords->tips) tip_names.push_back(tip.name);
    for (const Cord& cord : valve_case.cords->cords) {
      attachments.push_back({cord.vertex, cord.kind, cord.point});
      subset.push_back(cord.tip);
      compliance.push_back(cord.compliance);
    }
  } else {
    attachments = placeCordAttachments(mesh, options);
    std::vector<int> vertices;
    for (const CordAttachment& a : attachments) vertices.push_back(a.vertex);
    if (valve_case.tips && !valve_case.tips->empty()) {
      // Tips given without cords: each cord goes to the tip nearest in the annulus plane.
      tip_names.clear();
      for (const PmTip& tip : *valve_case.tips) tip_names.push_back(tip.name);
      subset = nearestTipInPlane(mesh, frame.plane, *valve_case.tips, vertices);
    } else {
      subset = splitBySide(mesh, frame, vertices);
    }
    for (const CordAttachment& a : attachments)
      compliance.push_back(a.kind == CordKind::kSecondary ? options.secondary_compliance_mm_per_n
                                                          : options.primary_compliance_mm_per_n);
  }

  std::vector<Eigen::Vector3d> insertions;
  for (const CordAttachment& a : attachments) {
    insertions.push_back(a.point ? pointPosition(*a.point, mesh.V)
                                 : Eigen::Vector3d(mesh.V.row(a.vertex)));
  }
  CordSet set;
  const bool tips_given = valve_case.tips && valve_case.tips->size() == tip_names.size();
  for (std::size_t t = 0; t < tip_names.size(); ++t) {
    std::vector<Eigen::Vector3d> members;
    for (std::size_t i = 0; i < attachments.size(); ++i) {
      if (subset[i] == static_cast<int>(t)) members.push_back(insertions[i]);
    }
    PmTip tip;
    tip.name = tip_names[t];
    if (tips_given) {
      tip = (*valve_case.tips)[t];
    } else {
      tip.position = heuristicTipPosition(frame.plane, members);
    }
    set.tips.push_back(tip);
  }
  for (std::size_t i = 0; i < attachments.size(); ++i) {
    Cord cord;
    cord.tip = subset[i];
    cord.vertex = attachments[i].vertex;
    cord.point = attachments[i].point;
    cord.kind = attachments[i].kind;
    cord.seed_rest_length =
        heuristicRestLength(insertions[i], frame.plane, set.tips[cord.tip].position);
    cord.rest_length = cord.seed_rest_length;
    cord.compliance = compliance[i];
    cord.provenance = Provenance::kHeuristic;
    set.cords.push_back(cord);
  }
  return set;
}

}  // namespace chordfit
