// Chordae model: papillary-muscle (PM) tips and the cords tying them to leaflet vertices.
// A CordSet is its own JSON file (cordset_io.h) so that heuristic, manual and fitted cord
// sets of one case can be kept side by side and compared.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace chordfit {

enum class CordKind { kPrimary, kSecondary };  // primary: near the free edge; secondary: belly
enum class Provenance { kHeuristic, kManual, kFitted };

struct PmTip {
  std::string name;  // mitral default: "anterolateral", "posteromedial"
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // open state, mm
  // Closed-state position; when present the simulator interpolates open -> closed,
  // otherwise the tip is static (paper: heuristic tips are static).
  std::optional<Eigen::Vector3d> closed_position;
};

// A cord's insertion between mesh vertices: the point sum_m weights(m) V(vertices[m]) of a
// triangle (barycentric weights >= 0, summing to 1). The synthetic cohort attaches its cords
// at anatomical points this way, so that the same point is meant on meshes of any resolution
// (core/cord_attachments.h); the paper's editor and the heuristic attach at vertices.
struct CordPoint {
  std::array<int, 3> vertices{};
  Eigen::Vector3d weights = Eigen::Vector3d(1.0, 0.0, 0.0);
};

struct Cord {
  int tip = 0;  // index into CordSet::tips
  // Leaflet vertex index into ValveMesh::V: where the cord inserts, or, with a point, the
  // point's vertex of largest weight (which then decides the cord's leaflet and segment).
  int vertex = 0;
  std::optional<CordPoint> point;  // insertion between vertices; absent = at `vertex`
  CordKind kind = CordKind::kPrimary;
  // Rest length l0 (mm) = seed_rest_length * scale. The seed is what the heuristic (or the
  // user's first definition) gave; a scale multiplies it (paper: "scale cord lengths").
  double seed_rest_length = 0.0;
  double rest_length = 0.0;
  double compliance = 0.0;  // XPBD compliance, mm/N; 0 = inextensible (paper eq. 1, alpha^CT = 0)
  Provenance provenance = Provenance::kHeuristic;
  bool locked = false;  // a manual override the fitter must not change

  double scale() const { return seed_rest_length > 0.0 ? rest_length / seed_rest_length : 1.0; }
};

struct CordSet {
  std::vector<PmTip> tips;
  std::vector<Cord> cords;
};

const char* toString(CordKind kind);
const char* toString(Provenance provenance);
std::optional<CordKind> parseCordKind(const std::string& text);
std::optional<Provenance> parseProvenance(const std::string& text);

// Group of a cord = (leaflet of its vertex, tip); the paper's four groups are
// anterior/posterior x anterolateral/posteromedial. Returns "<leaflet>/<tip>".
std::string groupName(const Cord& cord, const Eigen::VectorXi& leaflet_labels,
                      const std::vector<std::string>& leaflet_names,
                      const std::vector<PmTip>& tips);

// What is wrong with a point on a mesh of `vertex_count` vertices: a vertex index out of range,
// a negative or non-finite weight, or weights not summing to 1 (within 1e-9). "" = fine.
std::string cordPointProblem(const CordPoint& point, int vertex_count);

// Whether a cord's insertion (valid indices) lies on the annulus ring `ring` (vertex indices):
// when its vertices off the ring carry less than kMinLeafletInsertionWeight of its weight, a
// problem naming the weight on the ring; "" = fine. The closure moves ring vertices along a
// prescribed path, so such a cord pulls on nothing, or, through a vertex of weight b, moves
// that vertex 1/b times as far as the insertion: a 1e-12 weight threw it 1e12 times the
// cord's stretch at the first step. Every cord of the bundled and benchmark cases inserts
// wholly off the ring. Half the weight bounds that throw at twice the insertion's own move and
// keeps the insertion nearer the leaflet than the ring; it refuses only insertions within half
// a triangle of the ring, where no chorda inserts (the rough zone lies 5 mm and more from it).
constexpr double kMinLeafletInsertionWeight = 0.5;
std::string cordOnRingProblem(const Cord& cord, const Eigen::VectorXi& ring);

// A point on a mesh state V (#V by 3): sum_m weights(m) V(vertices[m]).
Eigen::Vector3d pointPosition(const CordPoint& point, const Eigen::MatrixXd& V);

// Where a cord inserts on a mesh state V: its point, else its vertex.
Eigen::Vector3d insertionPosition(const Cord& cord, const Eigen::MatrixXd& V);

// Slack by more than this at the closed state (closedSpans, cord_insertion.h; mm): an inextensible
// taut cord ends within the solver's tolerance of its rest length, far inside it.
constexpr double kSlackMarginMm = 0.01;

// A cord of rest length `rest_length` whose span in a closed state is `span` (closedSpans)
// pulls on nothing there: slack by more than kSlackMarginMm. The one definition the fit's
// report and its slack release share.
inline bool slackAtSpan(double span, double rest_length) {
  return span < rest_length - kSlackMarginMm;
}

// Editing, as in the paper's editor: a scale multiplies the seed rest length. Edited cords
// become provenance kManual. Locked cords are left alone and counted in the return value.
// Returns the number of cords changed.
int scaleCord(CordSet& set, int cord_index, double scale);
int scaleGroup(CordSet& set, const Eigen::VectorXi& leaflet_labels, int leaflet, int tip,
               double scale);
int scaleAllCords(CordSet& set, double scale);

}  // namespace chordfit
