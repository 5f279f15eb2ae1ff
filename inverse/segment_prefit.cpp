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
  const int segment_count = vertex_segment.size() > 0 ? vertex_segment.maxCoeff() + 1 : 0;
  for (int segment = 0; segment < segment_count; ++segment) {
    bool has_free = false;
    for (const Cord& cord : result.start.cords) {
      if (isFreeNonManual(cord) && vertex_segment(cord.vertex) == segment) has_free = true;
    }
    if (!has_free) continue;
    std::vector<double> scales;
    std::vector<CordSet> sets;
    for (int i = 0; i < points; ++i) {
      const double t = bounds.scale_lower + i * spacing;
      scales.push_back(t);
      sets.push_back(withSegmentScale(result.start, vertex_segment, segment, t));
    }
    std::vector<ForwardEvaluation> evaluations =
        closeCordSets(valve_case, sets, residual, options.threads, options.on_closure);
    result.forward_sims += static_cast<int>(sets.size());
    const int best = cheapestBelow(evaluations, result.best.cost);
    if (best < 0) continue;
    result.start = std::move(sets[best]);
    result.best = std::move(evaluations[best]);
    std::ostringstream change;
    change << segmentName(valve_case.mesh.leaflet_names, segment) << " " << scales[best];
    result.changed.push_back(change.str());
    result.changed_segments.push_back(segment);
  }
  return result;
}

}  // namespace chordfit::inverse
