#include "inverse/segment_prefit.h"

#include <algorithm>
#include <sstream>

#include "core/carpentier.h"
#include "core/metrics.h"
#include "inverse/global_prefit.h"

namespace chordfit::inverse {

namespace {

// `set` with every free cord of segment `segment` at scale t (rest = seed rest * t).
CordSet withSegmentScale(const CordSet& set, const Eigen::VectorXi& vertex_segment, int segment,
                         double t) {
  CordSet out = set;
  for (Cord& cord : out.cords) {
    if (isFreeNonManual(cord) && vertex_segment(cord.vertex) == segment) {
      cord.rest_length = cord.seed_rest_length * t;
    }
  }
  return out;
}

}  // namespace

SegmentPrefitResult segmentScalePrefit(const ValveCase& valve_case, const CordSet& start,
                                       const ForwardEvaluation& start_evaluation,
                                       const ParameterBounds& bounds,
                                       const ForwardResidual& residual,
                                       const SegmentPrefitOptions& options) {
  SegmentPrefitResult result;
  result.start = start;
  result.best = start_evaluation;
  if (!options.enabled) return result;
  const Eigen::VectorXi vertex_segment = openStateSegments(valve_case.mesh);
  const int points = std::max(2, options.points);
  const double spacing = (bounds.scale_upper - bounds.scale_lower) / (points - 1);
  SegmentMap names;  // only for segmentName
  names.leaflet_names = valve_case.mesh.leaflet_names;
  int segment_count = 0;
  for (Eigen::Index v = 0; v < vertex_segment.size(); ++v) {
    segment_count = std::max(segment_count, vertex_segment(v) + 1);
  }
  auto changeText = [&](int segment, double t) {
    std::ostringstream change;
    change << segmentName(names, segment) << " " << t;
    return change.str();
  };

  // Stage 1: every segment's grid from the same start, all closures in one parallel batch.
  std::vector<int> candidate_segment;
  std::vector<double> candidate_scale;
  std::vector<CordSet> sets;
  for (int segment = 0; segment < segment_count; ++segment) {
    bool has_free = false;
    for (const Cord& cord : start.cords) {
      if (isFreeNonManual(cord) && vertex_segment(cord.vertex) == segment) has_free = true;
    }
    if (!has_free) continue;
    for (int i = 0; i < points; ++i) {
      const double t = bounds.scale_lower + i * spacing;
      candidate_segment.push_back(segment);
      candidate_scale.push_back(t);
      sets.push_back(withSegmentScale(start, vertex_segment, segment, t));
    }
  }
  std::vector<ForwardEvaluation> evaluations =
      closeCordSets(valve_case, sets, residual, options.threads);
  result.forward_sims += static_cast<int>(sets.size());

  // Each segment's best grid point that beats the start, ordered by cost (ties: Carpentier
  // order, then the smaller scale, as the candidates were listed).
  struct Gain {
    double cost;
    int candidate;
  };
  std::vector<Gain> gains;
  for (int segment = 0; segment < segment_count; ++segment) {
    int best = -1;
    for (std::size_t k = 0; k < sets.size(); ++k) {
      if (candidate_segment[k] != segment || !evaluations[k].ok()) continue;
      const double bar = best < 0 ? start_evaluation.cost : evaluations[best].cost;
      if (evaluations[k].cost < bar) best = static_cast<int>(k);
    }
    if (best >= 0) gains.push_back({evaluations[best].cost, best});
  }
  std::stable_sort(gains.begin(), gains.end(),
                   [](const Gain& a, const Gain& b) { return a.cost < b.cost; });
  if (gains.empty()) return result;

  // Stage 2: take the best segment change, then add the others in order of their own gain,
  // each kept only if the combination lowers the cost (one closure each).
  const int first = gains.front().candidate;
  result.start = sets[first];
  result.best = std::move(evaluations[first]);
  result.changed.push_back(changeText(candidate_segment[first], candidate_scale[first]));
  for (std::size_t g = 1; g < gains.size(); ++g) {
    const int k = gains[g].candidate;
    CordSet combined =
        withSegmentScale(result.start, vertex_segment, candidate_segment[k], candidate_scale[k]);
    std::vector<ForwardEvaluation> check = closeCordSets(valve_case, {combined}, residual, 1);
    result.forward_sims += 1;
    if (cheapestBelow(check, result.best.cost) < 0) continue;
    result.start = std::move(combined);
    result.best = std::move(check.front());
    result.changed.push_back(changeText(candidate_segment[k], candidate_scale[k]));
  }
  return result;
}

}  // namespace chordfit::inverse
