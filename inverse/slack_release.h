// Slack-cord release: the last step of a per-cord optimisation (cord_optimisation.h).
//
// Why: a cord slack in the fitted closure (its span short of its rest length by more than
// kSlackMarginMm) pulls on nothing there, so every length from its span up closes the valve
// the same way; the tracings bound it from below only (the report's "(slack)"). Its fitted
// value is then whatever the priors left: the lower scale bound, or the scale a segment
// pre-fit gave its segment while the cord was still taut. Measured on the benchmark
// (experiments/, revision ea9bb3f), the slack cords near the tracing planes ended a median
// 8.5 % short of their true length, a fifth of them at the bound 0.7.
//
// What: each free, non-manual slack cord whose scale (rest length / seed rest length) lies
// below the typical scale of its kind on this valve is raised to it. The typical scale is
// the median scale of the taut cords of that kind outside the atypical segments, those the
// segment pre-fit rescaled and those prolapsing in the fitted closure (a prolapsing segment's
// elongated cords would drag it up: at the make-case default edge prolapse-P2 seed 3's P2
// primaries, taut and never rescaled, set it at 1.05 where the truth's other primaries sit at
// ~0.8): the valve's own taut cords are the data's estimate of where cords of the kind sit,
// an empirical prior. A raised
// cord is longer than before, so it stays slack in the fitted closed state; optimise() keeps the
// release only when a full closure with it fits the tracings as well (data cost within
// SlackReleaseOptions::cost_tolerance), since on the way from the open state a cord may pull
// before it goes slack. Manual and locked cords are never touched.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/case_data.h"
#include "core/cordset.h"

namespace chordfit::inverse {

struct SlackReleaseOptions {
  bool enabled = true;
  // Keep the release when its closure's data cost is at most (1 + tolerance) x the fit's.
  double cost_tolerance = 1e-3;
};

struct SlackReleaseProposal {
  std::vector<int> cords;      // released cord indices, ascending
  std::vector<double> scales;  // their new scales (rest length / seed rest length)
  // Typical scale of each kind (median over its taut reference cords); 0 when the kind has
  // no taut cord outside the excluded segments.
  double primary_reference = 0.0, secondary_reference = 0.0;
  bool empty() const { return cords.empty(); }
};

// fitted        the fitted set; seed: the set the fit started from (its provenance decides
//               which cords are free and not manual)
// closed_spans  #cords each fitted cord's span in the fitted closure (closedSpans)
// cord_segment  #cords each cord's Carpentier segment id (openStateSegments of its vertex)
// excluded_segments  segment ids whose cords do not enter the typical scale (the atypical ones)
// scale_upper   the fit's upper scale bound (a raised scale never exceeds it)
// The atypical segment ids: `rescaled` (those the segment pre-fit rescaled) and the segments
// prolapsing in the closed state closed_V of valve_case (prolapseOfMesh: their taut cords are
// the elongated ones that hold a flap).
std::vector<int> atypicalSegments(const ValveCase& valve_case, const Eigen::MatrixXd& closed_V,
                                  std::vector<int> rescaled);

// What the fit did with a proposal: its closure, and whether it was kept.
struct SlackReleaseOutcome {
  SlackReleaseProposal proposal;  // made at the optimiser's best point
  bool ran = false;               // the proposal was made (enabled, not groups, budget left)
  bool kept = false;              // its closure fitted no worse (then the fit's result)
  // The data costs (without regularisation) of the released and of the optimiser's closures.
  double data_cost = 0.0, optimiser_data_cost = 0.0;
  std::string error;  // its closure failed (then not kept)
};

SlackReleaseProposal proposeSlackRelease(const CordSet& fitted, const CordSet& seed,
                                         const Eigen::VectorXd& closed_spans,
                                         const std::vector<int>& cord_segment,
                                         const std::vector<int>& excluded_segments,
                                         double scale_upper);

}  // namespace chordfit::inverse
