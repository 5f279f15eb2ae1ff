// The fit's parameter vector and its mapping to a CordSet (DESIGN §7, issue 5 item 1).
//
// Modes:
//   scales       one rest-length scale per free (unlocked) cord;
//   groups       one factor per cord group (leaflet x PM tip, the paper's manual workflow);
//   scales+tips  per-cord scales, then three PM tip offsets (mm) per tip.
// A scale parameter is the cord's scale() = rest_length / seed_rest_length, so its bounds are
// the issue's [0.7, 1.5] in the paper's units. A group factor multiplies the group's starting
// rest lengths (for a heuristic seed, all scales 1, it is the group's scale); its bounds are
// the scale bounds divided by the group's mean starting scale. A tip offset
// moves the tip's open and (when given) closed position by the same vector.
// Locked cords are not parameters: apply() copies them from the start set untouched, so their
// rest length is kept bit for bit.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/case_data.h"
#include "core/cordset.h"

namespace chordfit::inverse {

enum class ParameterMode { kScales, kGroups, kScalesAndTips };

const char* toString(ParameterMode mode);
std::optional<ParameterMode> parseParameterMode(const std::string& text);  // "scales", ...

struct ParameterBounds {
  double scale_lower = 0.7;  // issue 5: per-cord scales bounded to [0.7, 1.5]
  double scale_upper = 1.5;
  double tip_box_mm = 8.0;  // each tip offset coordinate in [-box, +box]
};

// value, moved onto a bound it misses by rounding only: a pre-fit's or an edit's rest length
// seed * 0.7 gives scale() = 0.69999999999999984, which is on the bound 0.7, not beyond it.
double snapToBoundWithinRounding(double value, double lo, double hi);

class FitParameterization {
 public:
  // `start`: the cord set the fit starts from (heuristic or the user's edits). Its free cords'
  // current values are the starting point; start values outside the bounds are clamped.
  FitParameterization(const ValveCase& valve_case, const CordSet& start, ParameterMode mode,
                      const ParameterBounds& bounds);

  int size() const { return static_cast<int>(names_.size()); }
  ParameterMode mode() const { return mode_; }
  const Eigen::VectorXd& initial() const { return initial_; }
  const Eigen::VectorXd& lower() const { return lower_; }
  const Eigen::VectorXd& upper() const { return upper_; }
  // Initial step sizes for derivative-free optimisers and the finite-difference steps are
  // chosen per kind: true for a scale or group factor, false for a tip offset (mm).
  bool isScale(int parameter) const { return parameter < scale_count_; }
  const std::vector<std::string>& names() const { return names_; }  // "cord 3", "group ..."

  // The start set with parameters x applied. Cords whose rest length changed become
  // provenance kFitted; locked cords and unchanged cords keep everything.
  CordSet apply(const Eigen::VectorXd& x) const;

  // Per-cord parameter index (-1 for locked cords, or in groups mode the group parameter).
  const std::vector<int>& cordParameter() const { return cord_parameter_; }
  // First of the three offset parameters of tip t, or -1.
  int tipParameter(int tip) const;
  const CordSet& start() const { return start_; }
  // True when some start value lay outside the bounds (apply(initial()) != start then).
  bool startClamped() const {
    return initial_ !=
           Eigen::Map<const Eigen::VectorXd>(unclamped_start_.data(), unclamped_start_.size());
  }

 private:
  CordSet start_;
  ParameterMode mode_;
  std::vector<int> cord_parameter_;
  int scale_count_ = 0;
  int tip_offset_first_ = -1;
  std::vector<std::string> names_;
  Eigen::VectorXd initial_, lower_, upper_;
  std::vector<double> unclamped_start_;  // per parameter, before clamping to the bounds
};

// Every cord's group name (leaflet/tip) in a set, for reports and the groups mode.
std::vector<std::string> cordGroups(const ValveCase& valve_case, const CordSet& cords);

}  // namespace chordfit::inverse
