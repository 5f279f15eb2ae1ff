#include "inverse/forward_residual.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

#include "core/annulus_plane.h"
#include "core/carpentier.h"
#include "core/closure_model.h"
#include "core/metrics.h"
#include "core/tracing_sampler.h"
#include "inverse/robust_loss.h"

namespace chordfit::inverse {

std::vector<std::pair<int, int>> neighbouringCords(const ValveCase& valve_case,
                                                   const FitParameterization& parameters) {
  std::vector<std::pair<int, int>> pairs;
  if (parameters.mode() == ParameterMode::kGroups) return pairs;
  const CordSet& start = parameters.start();
  const std::vector<std::string> groups = cordGroups(valve_case, start);
  const AnnulusFrame frame = openAnnulusFrame(valve_case.mesh);
  // (group, kind) -> [(angle, cord)]
  std::map<std::pair<std::string, int>, std::vector<std::pair<double, int>>> chains;
  for (std::size_t c = 0; c < start.cords.size(); ++c) {
    if (parameters.cordParameter()[c] < 0) continue;
    const Cord& cord = start.cords[c];
    const double angle = annulusAngle(frame, insertionPosition(cord, valve_case.mesh.V));
    chains[{groups[c], static_cast<int>(cord.kind)}].push_back({angle, static_cast<int>(c)});
  }
  for (auto& [key, chain] : chains) {
    // Along the annulus: sorted by angle, then opened at the widest angular gap, so that a
    // group across atan2's cut at +-pi (the cut is at mid-P2; with a case's own tips a
    // posterior group can cross it) is ordered too. A group spans well under pi, so for one that
    // does not cross the cut the widest gap is the wrap-around one and the order is the sort's.
    std::sort(chain.begin(), chain.end());
    std::size_t first = 0;
    double widest = -1.0;
    for (std::size_t i = 0; i < chain.size(); ++i) {
      const double gap = i == 0 ? chain.front().first + 2.0 * M_PI - chain.back().first
                                : chain[i].first - chain[i - 1].first;
      if (gap > widest) {
        widest = gap;
        first = i;
      }
    }
    std::rotate(chain.begin(), chain.begin() + static_cast<std::ptrdiff_t>(first), chain.end());
    for (std::size_t i = 1; i < chain.size(); ++i) {
      pairs.push_back({chain[i - 1].second, chain[i].second});
    }
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

ForwardResidual::ForwardResidual(const ValveCase& valve_case, const FitParameterization& parameters,
                                 const SimulationSettings& settings, const ResidualOptions& options)
    : case_(valve_case),
      parameters_(parameters),
      settings_(settings),
      insertions_(chordfit::cordInsertions(valve_case.mesh, parameters.apply(parameters.initial()),
                                           settings.cord_insertion_radius_mm)),
      options_(options),
      face_leaflets_(faceLeaflets(valve_case.mesh.F, valve_case.mesh.leaflet)),
      sections_(valve_case, options.section),
      neighbours_(neighbouringCords(valve_case, parameters)) {
  tracing_points_ = stackTracingPoints(valve_case.tracings, &tracing_leaflets_);
  settings_.progress_every = 0;
  settings_.progress = nullptr;
  const int n = parameters.size();
  const Eigen::VectorXd& x0 = parameters.initial();
  std::vector<Eigen::VectorXd> rows;
  std::vector<double> rhs;
  auto addRow = [&](const Eigen::VectorXd& row) {
    rows.push_back(row);
    rhs.push_back(row.dot(x0));  // every term is zero at the start: r = row . (x - x0)
  };
  for (int p = 0; p < n; ++p) {
    Eigen::VectorXd row = Eigen::VectorXd::Zero(n);
    row(p) = parameters.isScale(p) ? options.weights.seed : options.weights.tip_per_mm;
    if (row(p) != 0.0) addRow(row);
  }
  if (options.weights.neighbour != 0.0) {
    for (const auto& [c, d] : neighbours_) {
      Eigen::VectorXd row = Eigen::VectorXd::Zero(n);
      row(parameters.cordParameter()[c]) += options.weights.neighbour;
      row(parameters.cordParameter()[d]) -= options.weights.neighbour;
      addRow(row);
    }
  }
  A_.resize(static_cast<Eigen::Index>(rows.size()), n);
  b_.resize(static_cast<Eigen::Index>(rows.size()));
  for (std::size_t r = 0; r < rows.size(); ++r) {
    A_.row(r) = rows[r].transpose();
    b_(r) = rhs[r];
  }
}

Eigen::VectorXd ForwardResidual::dataResiduals(const Eigen::MatrixXd& closed_V) const {
  Eigen::VectorXd data(dataCount());
  data.head(pointCount()) = options_.own_leaflet
                                ? pointToOwnLeafletDistances(closed_V, case_.mesh.F, face_leaflets_,
                                                             tracing_points_, tracing_leaflets_)
                                : surfaceDistances(closed_V);
  if (sectionCount() > 0)
    data.tail(sectionCount()) = (options_.section_weight * sections_.excess(closed_V)).cwiseSqrt();
  return data;
}

Eigen::VectorXd ForwardResidual::surfaceDistances(const Eigen::MatrixXd& closed_V) const {
  return pointToSurfaceDistances(closed_V, case_.mesh.F, tracing_points_);
}

double ForwardResidual::meanDeviation(const Eigen::MatrixXd& closed_V,
                                      const Eigen::VectorXd& data) const {
  if (pointCount() == 0) return 0.0;
  return options_.own_leaflet ? surfaceDistances(closed_V).mean() : data.head(pointCount()).mean();
}

double ForwardResidual::cost(const Eigen::VectorXd& data,
                             const Eigen::VectorXd& regularisation) const {
  double sum = 0.0;
  for (Eigen::Index i = 0; i < data.size(); ++i) {
    sum +=
        i < pointCount() ? huberRho(data(i) * data(i), options_.huber_delta_mm) : data(i) * data(i);
  }
  return 0.5 * sum + 0.5 * regularisation.squaredNorm();
}

ForwardEvaluation ForwardResidual::evaluate(const Eigen::VectorXd& x,
                                            const Eigen::MatrixXd* warm_start) const {
  ForwardEvaluation e;
  e.x = x;
  e.warm_started = warm_start != nullptr;
  const CordSet cords = parameters_.apply(x);
  SimulationResult r = simulateClosure(case_, cords, settings_, warm_start);
  countClosure(r);
  if (!r.ok()) {
    e.error = r.error;
    return e;
  }
  e.converged = r.converged;
  e.closed_V = std::move(r.V);
  e.data = dataResiduals(e.closed_V);
  e.regularisation = regularisation(x);
  e.cost = cost(e.data, e.regularisation);
  e.mean_deviation_mm = meanDeviation(e.closed_V, e.data);
  return e;
}

}  // namespace chordfit::inverse
