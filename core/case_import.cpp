#include "core/case_import.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "core/graph_distance.h"
#include "core/mesh_topology.h"

namespace chordfit {
namespace {

constexpr int kAnterior = 0, kPosterior = 1;

std::string mm(double value) {
  char text[32];
  // %.2f of an absurd distance (a landmark at 1e308) would print hundreds of digits.
  std::snprintf(text, sizeof text, std::abs(value) < 1e6 ? "%.2f mm" : "%.3g mm", value);
  return text;
}

// `out` with the error `what` about the input `input` (for the landmarks, those at fault).
ImportedCase failed(ImportedCase out, ImportInput input, std::string what,
                    std::vector<int> landmarks = {}) {
  out.error = std::move(what);
  out.error_input = input;
  out.error_landmarks = std::move(landmarks);
  return out;
}

// Index into `loop` of the vertex nearest to p, and its distance.
int nearestInLoop(const Eigen::MatrixXd& V, const std::vector<int>& loop, const Eigen::Vector3d& p,
                  double& distance) {
  int best = 0;
  distance = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < loop.size(); ++k) {
    // stableNorm: norm() overflows to inf for a landmark near 1e308 ("is inf mm from ...").
    const double d = (V.row(loop[k]).transpose() - p).stableNorm();
    if (d < distance) {
      distance = d;
      best = static_cast<int>(k);
    }
  }
  return best;
}

// A closed polyline parametrised by arc length.
class ClosedPolyline {
 public:
  explicit ClosedPolyline(const Eigen::MatrixXd& points) : points_(points) {
    const Eigen::Index n = points.rows();
    start_.resize(n + 1, 0.0);
    for (Eigen::Index k = 0; k < n; ++k) {
      start_[k + 1] = start_[k] + (points.row((k + 1) % n) - points.row(k)).norm();
    }
  }
  double length() const { return start_.back(); }
  // Arc length of the vertex nearest to p.
  double nearest(const Eigen::Vector3d& p) const {
    Eigen::Index best = 0;
    (points_.rowwise() - p.transpose()).rowwise().squaredNorm().minCoeff(&best);
    return start_[best];
  }
  // Point at arc length s (any real; wrapped).
  Eigen::Vector3d at(double s) const {
    const double L = length();
    s = std::fmod(s, L);
    if (s < 0.0) s += L;
    const Eigen::Index n = points_.rows();
    Eigen::Index k = 0;
    while (k + 1 < n && start_[k + 1] <= s) ++k;
    const double span = start_[k + 1] - start_[k];
    const double u = span > 0.0 ? (s - start_[k]) / span : 0.0;
    return (1.0 - u) * points_.row(k).transpose() + u * points_.row((k + 1) % n).transpose();
  }

 private:
  Eigen::MatrixXd points_;
  std::vector<double> start_;  // arc length at each vertex; back() = total
};

// Closed positions of the ring, traversed from ring index `al` (j = 0 .. n-1), with the
// commissure at traversal step `pm_step` (the first arc is j in [0, pm_step]).
Eigen::MatrixXd resampleClosedRing(const Eigen::MatrixXd& V, const std::vector<int>& ring, int al,
                                   int pm_step, const Eigen::MatrixXd& closed_curve,
                                   std::string& error) {
  const int n = static_cast<int>(ring.size());
  const auto vertex = [&](int j) { return Eigen::Vector3d(V.row(ring[(al + j) % n])); };
  // Open arc length along the traversal.
  std::vector<double> s(n + 1, 0.0);
  for (int j = 0; j < n; ++j) s[j + 1] = s[j] + (vertex(j + 1) - vertex(j)).norm();
  const double open_first = s[pm_step], open_total = s[n];

  const ClosedPolyline curve(closed_curve);
  const double L = curve.length();
  if (!(L > 0.0)) {
    error = "the closed annulus curve has zero length";
    return {};
  }
  const double c_al = curve.nearest(vertex(0)), c_pm = curve.nearest(vertex(pm_step));
  if (c_al == c_pm) {
    error = "both commissures are nearest to the same point of the closed annulus curve";
    return {};
  }
  Eigen::MatrixXd best;
  double best_cost = std::numeric_limits<double>::infinity();
  for (const double direction : {1.0, -1.0}) {
    double first = direction * (c_pm - c_al);  // closed arc length AL -> PM along `direction`
    first = std::fmod(first + 2.0 * L, L);
    Eigen::MatrixXd closed(n, 3);
    double cost = 0.0;
    for (int j = 0; j < n; ++j) {
      const double t = s[j] <= open_first
                           ? first * s[j] / open_first
                           : first + (L - first) * (s[j] - open_first) / (open_total - open_first);
      const Eigen::Vector3d p = curve.at(c_al + direction * t);
      closed.row((al + j) % n) = p.transpose();
      cost += (p - vertex(j)).squaredNorm();
    }
    if (cost < best_cost) {
      best_cost = cost;
      best = closed;
    }
  }
  return best;
}

}  // namespace

ImportedCase importValveCase(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                             const ImportLandmarks& landmarks, const Eigen::MatrixXd& closed_curve,
                             const std::string& name) {
  ImportedCase out;
  // The caller checks the mesh (checkValveMesh); the walk below would read past V otherwise.
  if (F.size() > 0 && (F.minCoeff() < 0 || F.maxCoeff() >= V.rows())) {
    return failed(std::move(out), ImportInput::kMesh,
                  "a face's vertex index is out of range (mesh has " + std::to_string(V.rows()) +
                      " vertices)");
  }
  const std::vector<std::vector<int>> loops = boundaryLoops(F);
  if (loops.empty()) {
    return failed(std::move(out), ImportInput::kMesh,
                  "the mesh has no boundary loop (a valve surface has its annulus as a boundary)");
  }
  // NaN passes every distance bound below (comparisons with it are false).
  const std::pair<const char*, const Eigen::Vector3d*> named[] = {
      {"anterolateral commissure", &landmarks.anterolateral},
      {"posteromedial commissure", &landmarks.posteromedial},
      {"anterior", &landmarks.anterior}};
  for (int k = 0; k < 3; ++k) {
    if (!named[k].second->allFinite()) {
      return failed(std::move(out), ImportInput::kLandmarks,
                    std::string("the ") + named[k].first + " landmark is not a finite point", {k});
    }
  }
  // 1. The loop nearest to both commissures.
  std::size_t best_loop = 0;
  double best_sum = std::numeric_limits<double>::infinity();
  for (std::size_t l = 0; l < loops.size(); ++l) {
    double d_al = 0.0, d_pm = 0.0;
    nearestInLoop(V, loops[l], landmarks.anterolateral, d_al);
    nearestInLoop(V, loops[l], landmarks.posteromedial, d_pm);
    if (d_al + d_pm < best_sum) {
      best_sum = d_al + d_pm;
      best_loop = l;
    }
  }
  const std::vector<int>& ring = loops[best_loop];
  out.holes = holesBeyondRingAndFreeEdge(loops.size());
  const int n = static_cast<int>(ring.size());
  const int al = nearestInLoop(V, ring, landmarks.anterolateral, out.commissure_distance_mm[0]);
  const int pm = nearestInLoop(V, ring, landmarks.posteromedial, out.commissure_distance_mm[1]);
  static const char* kNames[] = {"anterolateral", "posteromedial"};
  for (int c = 0; c < 2; ++c) {
    if (out.commissure_distance_mm[c] > kMaxLandmarkDistanceMm) {
      return failed(std::move(out), ImportInput::kLandmarks,
                    std::string("the ") + kNames[c] + " commissure landmark is " +
                        mm(out.commissure_distance_mm[c]) +
                        " from the nearest boundary loop (at most " + mm(kMaxLandmarkDistanceMm) +
                        "): is it on the annulus?",
                    {c});
    }
  }
  if (al == pm) {
    return failed(std::move(out), ImportInput::kLandmarks,
                  "both commissure landmarks are nearest to the same annulus vertex " +
                      std::to_string(ring[al]),
                  {0, 1});
  }
  // 2. The arcs, traversed from AL: steps 0..pm_step, then pm_step..n.
  const int pm_step = (pm - al + n) % n;
  double d_anterior = 0.0;
  const int anterior_step = (nearestInLoop(V, ring, landmarks.anterior, d_anterior) - al + n) % n;
  if (!(d_anterior <= kMaxAnteriorLandmarkDistanceMm)) {
    return failed(std::move(out), ImportInput::kLandmarks,
                  "the anterior landmark is " + mm(d_anterior) +
                      " from the annulus ring (at most " + mm(kMaxAnteriorLandmarkDistanceMm) +
                      "): is it on the anterior annulus?",
                  {2});
  }
  if (anterior_step == 0 || anterior_step == pm_step) {
    return failed(std::move(out), ImportInput::kLandmarks,
                  "the anterior landmark is nearest to a commissure; place it on the anterior "
                  "annulus between the commissures",
                  {2});
  }
  const bool first_is_anterior = anterior_step < pm_step;
  Eigen::VectorXi labels = Eigen::VectorXi::Constant(V.rows(), -1);
  std::vector<int> sources[2];
  double arc_length[2] = {0.0, 0.0};
  for (int j = 0; j < n; ++j) {
    const bool in_first = j <= pm_step;
    const bool commissure = j == 0 || j == pm_step;
    const int leaflet = commissure || in_first == first_is_anterior ? kAnterior : kPosterior;
    labels(ring[(al + j) % n]) = leaflet;
    sources[leaflet].push_back(ring[(al + j) % n]);
    const double edge = (V.row(ring[(al + j + 1) % n]) - V.row(ring[(al + j) % n])).norm();
    arc_length[(j < pm_step) == first_is_anterior ? kAnterior : kPosterior] += edge;
  }
  if (sources[kPosterior].empty()) {
    // The commissures are neighbours on the ring.
    return failed(std::move(out), ImportInput::kLandmarks,
                  "no annulus vertex lies between the commissures on the posterior side", {0, 1});
  }
  out.anterior_fraction = arc_length[kAnterior] / (arc_length[kAnterior] + arc_length[kPosterior]);
  // 3. Labels of the other vertices: the leaflet whose annulus arc is nearer along the edges.
  const Eigen::VectorXd to_anterior = edgeGraphDistance(V, F, sources[kAnterior]);
  const Eigen::VectorXd to_posterior = edgeGraphDistance(V, F, sources[kPosterior]);
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    if (labels(v) >= 0) continue;
    if (!std::isfinite(to_anterior(v)) && !std::isfinite(to_posterior(v))) {
      return failed(std::move(out), ImportInput::kMesh,
                    "vertex " + std::to_string(v) + " is not connected to the annulus");
    }
    labels(v) = to_anterior(v) <= to_posterior(v) ? kAnterior : kPosterior;
  }
  // 4. Closed annulus.
  Eigen::MatrixXd ring_open(n, 3);
  for (int k = 0; k < n; ++k) ring_open.row(k) = V.row(ring[k]);
  Eigen::MatrixXd closed = ring_open;
  if (closed_curve.rows() > 0) {
    if (closed_curve.rows() < 3) {
      return failed(std::move(out), ImportInput::kClosedAnnulus,
                    "the closed annulus curve needs at least 3 points");
    }
    std::string curve_error;
    closed = resampleClosedRing(V, ring, al, pm_step, closed_curve, curve_error);
    if (!curve_error.empty())
      return failed(std::move(out), ImportInput::kClosedAnnulus, curve_error);
  }
  out.closed_shift_mm = (closed - ring_open).rowwise().norm().mean();

  ValveCase& c = out.valve_case;
  c.name = name;
  c.mesh.V = V;
  c.mesh.F = F;
  c.mesh.leaflet = labels;
  c.mesh.annulus = Eigen::Map<const Eigen::VectorXi>(ring.data(), n);
  c.annulus_closed = closed;
  return out;
}

}  // namespace chordfit
