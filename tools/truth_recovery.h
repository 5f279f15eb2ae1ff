// How far a cord set lies from a synthetic case's truth (make-case writes it to
// CASE_DIR/truth/truth.json): the rest-length error of each cord against its true length, and
// each PM tip's distance from its true position. For `compare`, so that "manual vs
// optimised vs truth" needs no script. Cords correspond to the truth's one to one, in order
// (core/synthetic_case.h); a set with another cord count is not compared.
#pragma once

#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/cordset.h"

namespace chordfit::cli {

struct TrueCord {
  double rest_length_mm = 0.0;
  bool ruptured = false;  // no true length: the truth lengthens it tenfold
  bool taut = false;      // under tension in the true closed valve
  int case_vertex = -1;   // its insertion's vertex on the case mesh (-1: not given)
};

struct CaseTruth {
  std::vector<TrueCord> cords;
  std::vector<Eigen::Vector3d> tip_positions;  // in the order of the case's tips
  // Where the heuristic puts each tip on the case (what a fit starts from); empty when the
  // truth does not say.
  std::vector<Eigen::Vector3d> case_heuristic_tip_positions;
  // The truth's own AvgD against the tracings (truth/metrics.json mean_mm): the noise floor,
  // what no cord set closed on the case can be expected to beat. NaN when not given.
  double noise_floor_mm = std::numeric_limits<double>::quiet_NaN();
};

// The truth of the case in `case_dir` (its truth/truth.json), or nullopt when there is none.
// A truth.json that cannot be read gives nullopt and a warning on stderr naming the file and
// field: the comparison goes on without it.
std::optional<CaseTruth> readCaseTruth(const std::filesystem::path& case_dir);

struct TruthRecovery {
  std::string problem;                 // why the set was not compared ("" when it was)
  int cords = 0;                       // unruptured cords compared
  int taut_cords = 0;                  // of them, taut in the true closed valve
  double median_error_pct = 0.0;       // median |rest / true - 1| in %, over `cords`
  double median_error_taut_pct = 0.0;  // ... over `taut_cords` (NaN when none)
  double max_tip_offset_mm = 0.0;      // largest tip distance from its true position
  // The set's tips are the case's heuristic ones, unmoved (a fit of scales only): their offset
  // is the heuristic's, not a fitted one.
  bool heuristic_tips = false;
  // Per cord, in the set's order: rest / true - 1 in % (signed; NaN for a ruptured cord).
  std::vector<double> signed_error_pct;
};

TruthRecovery recoveryAgainstTruth(const CordSet& set, const CaseTruth& truth);

}  // namespace chordfit::cli
