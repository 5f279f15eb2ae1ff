#include "core/cordset.h"

#include <cmath>
#include <cstdio>

namespace chordfit {

const char* toString(CordKind kind) { return kind == CordKind::kPrimary ? "primary" : "secondary"; }

const char* toString(Provenance provenance) {
  switch (provenance) {
    case Provenance::kHeuristic:
      return "heuristic";
    case Provenance::kManual:
      return "manual";
    case Provenance::kFitted:
      return "fitted";
  }
  return "heuristic";
}

std::optional<CordKind> parseCordKind(const std::string& text) {
  if (text == "primary") return CordKind::kPrimary;
  if (text == "secondary") return CordKind::kSecondary;
  return std::nullopt;
}

std::optional<Provenance> parseProvenance(const std::string& text) {
  if (text == "heuristic") return Provenance::kHeuristic;
  if (text == "manual") return Provenance::kManual;
  if (text == "fitted") return Provenance::kFitted;
  return std::nullopt;
}

std::string groupName(const Cord& cord, const Eigen::VectorXi& leaflet_labels,
                      const std::vector<std::string>& leaflet_names,
                      const std::vector<PmTip>& tips) {
  std::string leaflet = "?";
  if (cord.vertex >= 0 && cord.vertex < leaflet_labels.size()) {
    const int label = leaflet_labels(cord.vertex);
    leaflet = (label >= 0 && label < static_cast<int>(leaflet_names.size()))
                  ? leaflet_names[label]
                  : std::to_string(label);
  }
  std::string tip = (cord.tip >= 0 && cord.tip < static_cast<int>(tips.size()))
                        ? tips[cord.tip].name
                        : std::to_string(cord.tip);
  return leaflet + "/" + tip;
}

namespace {
bool applyScale(Cord& cord, double scale) {
  if (cord.locked) return false;
  cord.rest_length = cord.seed_rest_length * scale;
  cord.provenance = Provenance::kManual;
  return true;
}
}  // namespace

int scaleCord(CordSet& set, int cord_index, double scale) {
  if (cord_index < 0 || cord_index >= static_cast<int>(set.cords.size())) return 0;
  return applyScale(set.cords[cord_index], scale) ? 1 : 0;
}

int scaleGroup(CordSet& set, const Eigen::VectorXi& leaflet_labels, int leaflet, int tip,
               double scale) {
  int changed = 0;
  for (Cord& cord : set.cords) {
    if (cord.tip != tip || cord.vertex < 0 || cord.vertex >= leaflet_labels.size()) continue;
    if (leaflet_labels(cord.vertex) != leaflet) continue;
    changed += applyScale(cord, scale) ? 1 : 0;
  }
  return changed;
}

std::string cordPointProblem(const CordPoint& point, int vertex_count) {
  for (int v : point.vertices) {
    if (v < 0 || v >= vertex_count) {
      return "vertex " + std::to_string(v) + " does not exist (mesh has " +
             std::to_string(vertex_count) + " vertices)";
    }
  }
  // A repeated vertex would enter the constraint's denominator twice (sum b_i^2 w instead of
  // (sum b_i)^2 w): the point then moves by the wrong amount.
  if (point.vertices[0] == point.vertices[1] || point.vertices[0] == point.vertices[2] ||
      point.vertices[1] == point.vertices[2])
    return "the three vertices must differ (a point at a vertex is given by \"vertex\" alone)";
  if (!point.weights.allFinite() || point.weights.minCoeff() < 0.0)
    return "weights must be finite and >= 0";
  if (std::abs(point.weights.sum() - 1.0) > 1e-9) return "weights must sum to 1";
  return "";
}

std::string cordOnRingProblem(const Cord& cord, const Eigen::VectorXi& ring) {
  const auto on_ring = [&ring](int v) { return (ring.array() == v).any(); };
  double leaflet_weight = 0.0;
  std::vector<int> ring_vertices;
  const auto add = [&](int v, double weight) {
    if (!on_ring(v)) {
      leaflet_weight += weight;
    } else if (weight > 0.0) {
      ring_vertices.push_back(v);
    }
  };
  if (cord.point) {
    for (int m = 0; m < 3; ++m) add(cord.point->vertices[m], cord.point->weights(m));
  } else {
    add(cord.vertex, 1.0);
  }
  if (leaflet_weight >= kMinLeafletInsertionWeight) return "";
  char share[32];
  std::snprintf(share, sizeof share, "%.4g %%", 100.0 * (1.0 - leaflet_weight));
  std::string named = ring_vertices.size() == 1 ? "ring vertex " : "ring vertices ";
  for (std::size_t k = 0; k < ring_vertices.size(); ++k)
    named += (k ? ", " : "") + std::to_string(ring_vertices[k]);
  return std::string("the insertion lies on the annulus ring (") + share + " of its weight on " +
         named +
         ", which the closure moves along a prescribed path): a cord must pull on the leaflet, "
         "with at least " +
         std::to_string(static_cast<int>(100 * kMinLeafletInsertionWeight)) +
         " % of its weight on vertices off the ring";
}

Eigen::Vector3d pointPosition(const CordPoint& p, const Eigen::MatrixXd& V) {
  return p.weights(0) * V.row(p.vertices[0]).transpose() +
         p.weights(1) * V.row(p.vertices[1]).transpose() +
         p.weights(2) * V.row(p.vertices[2]).transpose();
}

Eigen::Vector3d insertionPosition(const Cord& cord, const Eigen::MatrixXd& V) {
  return cord.point ? pointPosition(*cord.point, V) : Eigen::Vector3d(V.row(cord.vertex));
}

int scaleAllCords(CordSet& set, double scale) {
  int changed = 0;
  for (Cord& cord : set.cords) changed += applyScale(cord, scale) ? 1 : 0;
  return changed;
}

}  // namespace chordfit
