#include "inverse/fit_parameters.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace chordfit::inverse {

const char* toString(ParameterMode mode) {
  switch (mode) {
    case ParameterMode::kScales:
      return "scales";
    case ParameterMode::kGroups:
      return "groups";
    case ParameterMode::kScalesAndTips:
      return "scales+tips";
  }
  return "scales";
}

std::optional<ParameterMode> parseParameterMode(const std::string& text) {
  if (text == "scales") return ParameterMode::kScales;
  if (text == "groups") return ParameterMode::kGroups;
  if (text == "scales+tips") return ParameterMode::kScalesAndTips;
  return std::nullopt;
}

std::vector<std::string> cordGroups(const ValveCase& valve_case, const CordSet& cords) {
  std::vector<std::string> groups;
  for (const Cord& cord : cords.cords) {
    groups.push_back(
        groupName(cord, valve_case.mesh.leaflet, valve_case.mesh.leaflet_names, cords.tips));
  }
  return groups;
}

double snapToBoundWithinRounding(double value, double lo, double hi) {
  const double rounding = 1e-12 * std::max(1.0, std::max(std::abs(lo), std::abs(hi)));
  if (value < lo && value >= lo - rounding) return lo;
  if (value > hi && value <= hi + rounding) return hi;
  return value;
}

FitParameterization::FitParameterization(const ValveCase& valve_case, const CordSet& start,
                                         ParameterMode mode, const ParameterBounds& bounds)
    : start_(start), mode_(mode), cord_parameter_(start.cords.size(), -1) {
  std::vector<double> initial, lower, upper;
  auto add = [&](std::string name, double value, double lo, double hi) {
    names_.push_back(std::move(name));
    // Clamping a start beyond a bound by rounding only would mark it as moved, throw its known
    // closure away and cost a closure to redo it.
    value = snapToBoundWithinRounding(value, lo, hi);
    unclamped_start_.push_back(value);
    initial.push_back(std::clamp(value, lo, hi));
    lower.push_back(lo);
    upper.push_back(hi);
    return static_cast<int>(names_.size()) - 1;
  };
  if (mode == ParameterMode::kGroups) {
    const std::vector<std::string> groups = cordGroups(valve_case, start);
    std::map<std::string, int> index;  // group name -> parameter, in order of first cord
    for (std::size_t c = 0; c < start.cords.size(); ++c) {
      if (start.cords[c].locked) continue;
      auto found = index.find(groups[c]);
      if (found == index.end()) {
        // The factor multiplies the starting rest lengths; its bounds keep the group's mean
        // scale inside the scale bounds.
        double sum = 0.0;
        int count = 0;
        for (std::size_t d = 0; d < start.cords.size(); ++d) {
          if (!start.cords[d].locked && groups[d] == groups[c])
            sum += start.cords[d].scale(), ++count;
        }
        const double mean_scale = sum / count;
        found =
            index
                .emplace(groups[c], add("group " + groups[c], 1.0, bounds.scale_lower / mean_scale,
                                        bounds.scale_upper / mean_scale))
                .first;
      }
      cord_parameter_[c] = found->second;
    }
  } else {
    for (std::size_t c = 0; c < start.cords.size(); ++c) {
      const Cord& cord = start.cords[c];
      if (cord.locked) continue;
      cord_parameter_[c] =
          add("cord " + std::to_string(c), cord.scale(), bounds.scale_lower, bounds.scale_upper);
    }
  }
  scale_count_ = static_cast<int>(names_.size());
  if (mode == ParameterMode::kScalesAndTips && !start.tips.empty()) {
    tip_offset_first_ = scale_count_;
    static const char* kAxes[] = {"x", "y", "z"};
    for (const PmTip& tip : start.tips) {
      for (const char* axis : kAxes) {
        add("tip " + tip.name + " " + axis, 0.0, -bounds.tip_box_mm, bounds.tip_box_mm);
      }
    }
  }
  initial_ = Eigen::Map<Eigen::VectorXd>(initial.data(), initial.size());
  lower_ = Eigen::Map<Eigen::VectorXd>(lower.data(), lower.size());
  upper_ = Eigen::Map<Eigen::VectorXd>(upper.data(), upper.size());
}

int FitParameterization::tipParameter(int tip) const {
  return tip_offset_first_ < 0 ? -1 : tip_offset_first_ + 3 * tip;
}

CordSet FitParameterization::apply(const Eigen::VectorXd& x) const {
  CordSet set = start_;
  for (std::size_t c = 0; c < set.cords.size(); ++c) {
    const int p = cord_parameter_[c];
    if (p < 0) continue;                        // locked: untouched, bit for bit
    if (x(p) == unclamped_start_[p]) continue;  // unchanged: keep the start value exactly
    Cord& cord = set.cords[c];
    const double rest = mode_ == ParameterMode::kGroups ? start_.cords[c].rest_length * x(p)
                                                        : cord.seed_rest_length * x(p);
    if (rest != cord.rest_length) {
      cord.rest_length = rest;
      cord.provenance = Provenance::kFitted;
    }
  }
  for (std::size_t t = 0; t < set.tips.size(); ++t) {
    const int p = tipParameter(static_cast<int>(t));
    if (p < 0) continue;
    const Eigen::Vector3d offset = x.segment<3>(p);
    set.tips[t].position += offset;
    if (set.tips[t].closed_position) *set.tips[t].closed_position += offset;
  }
  return set;
}

}  // namespace chordfit::inverse
