#include "inverse/slack_release.h"

#include <algorithm>

#include "core/carpentier.h"
#include "core/metrics.h"
#include "inverse/global_prefit.h"

namespace chordfit::inverse {

std::vector<int> atypicalSegments(const ValveCase& valve_case, const Eigen::MatrixXd& closed_V,
                                  std::vector<int> rescaled) {
  const std::vector<std::string> prolapsing = prolapseOfMesh(valve_case, closed_V).segments;
  // Segment ids are leaflet * 3 + index (carpentier.h).
  const int segment_count = 3 * static_cast<int>(valve_case.mesh.leaflet_names.size());
  for (int id = 0; id < segment_count; ++id) {
    if (std::find(prolapsing.begin(), prolapsing.end(),
                  segmentName(valve_case.mesh.leaflet_names, id)) != prolapsing.end())
      rescaled.push_back(id);
  }
  return rescaled;
}

SlackReleaseProposal proposeSlackRelease(const CordSet& fitted, const CordSet& seed,
                                         const Eigen::VectorXd& closed_spans,
                                         const std::vector<int>& cord_segment,
                                         const std::vector<int>& excluded_segments,
                                         double scale_upper) {
  SlackReleaseProposal proposal;
  const std::size_t count = fitted.cords.size();
  if (seed.cords.size() != count || static_cast<std::size_t>(closed_spans.size()) != count ||
      cord_segment.size() != count) {
    return proposal;
  }
  auto scaleOf = [&](std::size_t c) {
    const Cord& cord = fitted.cords[c];
    return cord.seed_rest_length > 0.0 ? cord.rest_length / cord.seed_rest_length : 0.0;
  };
  auto slack = [&](std::size_t c) {
    return slackAtSpan(closed_spans(c), fitted.cords[c].rest_length);
  };
  auto excluded = [&](std::size_t c) {
    return std::find(excluded_segments.begin(), excluded_segments.end(), cord_segment[c]) !=
           excluded_segments.end();
  };

  double* reference_of[2] = {&proposal.primary_reference, &proposal.secondary_reference};
  const CordKind kinds[2] = {CordKind::kPrimary, CordKind::kSecondary};
  for (int k = 0; k < 2; ++k) {
    std::vector<double> taut;
    for (std::size_t c = 0; c < count; ++c) {
      if (fitted.cords[c].kind == kinds[k] && !slack(c) && !excluded(c) && scaleOf(c) > 0.0)
        taut.push_back(scaleOf(c));
    }
    if (!taut.empty()) *reference_of[k] = median(std::move(taut));
  }

  for (std::size_t c = 0; c < count; ++c) {
    const Cord& cord = fitted.cords[c];
    if (!isFreeNonManual(seed.cords[c]) || !slack(c) || cord.seed_rest_length <= 0.0) continue;
    const double reference = std::min(
        cord.kind == CordKind::kPrimary ? proposal.primary_reference : proposal.secondary_reference,
        scale_upper);
    // A scale within rounding of the reference is at it (0.6999999999999998 was "raised" to the
    // 0.7 of the lower bound, and a closure spent on it), as a bound within 1e-9 counts as
    // reached elsewhere in the fit.
    constexpr double kSameScale = 1e-9;
    if (!(reference > scaleOf(c) + kSameScale)) continue;
    proposal.cords.push_back(static_cast<int>(c));
    proposal.scales.push_back(reference);
  }
  return proposal;
}

}  // namespace chordfit::inverse
