#include "inverse/tissue_prefit.h"

#include <algorithm>
#include <atomic>
#include <sstream>

#include "core/carpentier.h"
#include "core/metrics.h"
#include "core/parallel_for.h"
#include "inverse/global_prefit.h"

namespace chordfit::inverse {

namespace {

struct Candidate {
  double factor = 1.0;
  bool long_cords = false;
  CordSet cords;
  Eigen::VectorXd tissue;
};

}  // namespace

TissuePrefitResult segmentTissuePrefit(const ValveCase& valve_case, const CordSet& start,
                                       const ForwardEvaluation& start_evaluation,
                                       const ParameterBounds& bounds,
                                       const ForwardResidual& residual,
                                       const TissuePrefitOptions& options) {
  TissuePrefitResult result;
  result.start = start;
  result.best = start_evaluation;
  if (!options.enabled || options.factors.empty()) return result;
  const Eigen::Index n = valve_case.mesh.V.rows();
  // The case's own tissue (uniform when it has none); accepted softenings multiply it.
  Eigen::VectorXd tissue = valve_case.tissue_stiffness.size() == n ? valve_case.tissue_stiffness
                                                                   : Eigen::VectorXd::Ones(n);
  const Eigen::VectorXi vertex_segment = openStateSegments(valve_case.mesh);
  const int segment_count = vertex_segment.size() > 0 ? vertex_segment.maxCoeff() + 1 : 0;

  // Greedy, best first: every segment's candidates from the same start, the best accepted;
  // then again for the segments not yet changed (a pass in a fixed order would let a
  // neighbour's softening, tried first, take a lesion's place).
  std::vector<bool> done(segment_count, false);
  std::atomic<int> closed{0};  // over all rounds, for on_closure
  const int most = options.closures(
      options.segments.empty() ? segment_count : static_cast<int>(options.segments.size()));
  for (int round = 0; round < options.rounds; ++round) {
    std::vector<Candidate> candidates;
    std::vector<int> candidate_segment;
    for (int segment = 0; segment < segment_count; ++segment) {
      if (done[segment]) continue;
      if (!options.segments.empty() && std::find(options.segments.begin(), options.segments.end(),
                                                 segment) == options.segments.end())
        continue;
      for (double f : options.factors) {
        for (bool long_cords : {false, true}) {
          Candidate c{f, long_cords, result.start, tissue};
          for (Eigen::Index v = 0; v < n; ++v) {
            if (vertex_segment(v) == segment) c.tissue(v) *= f;
          }
          bool changed_cords = false;
          if (long_cords) {
            for (Cord& cord : c.cords.cords) {
              if (isFreeNonManual(cord) && vertex_segment(cord.vertex) == segment) {
                cord.rest_length = cord.seed_rest_length * bounds.scale_upper;
                changed_cords = true;
              }
            }
            if (!changed_cords) continue;  // the same candidate as with the cords as they are
          }
          candidates.push_back(std::move(c));
          candidate_segment.push_back(segment);
        }
      }
    }
    std::vector<ForwardEvaluation> evaluations(candidates.size());
    parallelFor(static_cast<int>(candidates.size()), options.threads, [&](int i) {
      ValveCase softened = valve_case;
      softened.tissue_stiffness = candidates[i].tissue;
      evaluations[i] = closeForData(softened, candidates[i].cords, residual);
      if (options.on_closure) options.on_closure(++closed, most);
    });
    result.forward_sims += static_cast<int>(candidates.size());
    const int best = cheapestBelow(evaluations, result.best.cost);
    if (best < 0) break;
    done[candidate_segment[best]] = true;
    tissue = candidates[best].tissue;
    result.start = std::move(candidates[best].cords);
    result.best = std::move(evaluations[best]);
    std::ostringstream change;
    change << segmentName(valve_case.mesh.leaflet_names, candidate_segment[best]) << " "
           << candidates[best].factor;
    if (candidates[best].long_cords) change << ", cords " << bounds.scale_upper;
    result.changed.push_back(change.str());
  }
  if (!result.changed.empty()) result.tissue = tissue;
  return result;
}

}  // namespace chordfit::inverse
