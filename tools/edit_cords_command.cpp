// edit-cords: scale and lock cords as the paper's editor does, so a manual cord set can be
// made, fitted from (fit --seed-cords keeps locked cords and starts from the manual ones) and
// compared (compare heuristic.json manual.json fit/cords.json).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/carpentier.h"
#include "core/case_extent.h"
#include "core/cordset_io.h"
#include "core/counted.h"
#include "core/decimal_number.h"
#include "core/metrics.h"
#include "core/text_case.h"
#include "inverse/fit_parameters.h"
#include "tools/command_support.h"
#include "tools/commands.h"
#include "tools/staged_output.h"

namespace chordfit::cli {

namespace {

// Largest scale accepted: the cohort's most elongated cords are 2.5 x the heuristic's bound.
constexpr double kMaxScale = 10.0;
// The fit's default scale bounds (inverse/fit_parameters.h): an unlocked cord outside them
// starts the fit clamped.
// The fit's default scale bounds.
const double kFitScaleLower = inverse::ParameterBounds{}.scale_lower;
const double kFitScaleUpper = inverse::ParameterBounds{}.scale_upper;

int usage(const std::string& message) {
  std::cerr << "error: edit-cords: " << message << "\n";
  return kExitBadInput;
}

bool parseScale(const std::string& text, double& scale) {
  return parseDecimal(text, scale) && scale > 0.0 && scale <= kMaxScale;
}

// "NAME=S" -> name, scale; false with `problem` set otherwise.
bool splitAssignment(const std::string& option, const std::string& text, std::string& name,
                     double& scale, std::string& problem) {
  const std::size_t eq = text.rfind('=');
  if (eq == std::string::npos || eq == 0) {
    problem = option + " " + text + ": expected NAME=SCALE";
    return false;
  }
  name = text.substr(0, eq);
  if (!parseScale(text.substr(eq + 1), scale)) {
    problem = option + " " + text + ": the scale must be a number in (0, " +
              std::to_string(static_cast<int>(kMaxScale)) + "]";
    return false;
  }
  return true;
}

// Cord indices "3,5,7" (0-based, < count), or every cord for "all", or `edited` for "edited"
// when `allow_edited`. `option` names the argument in the problem ("--lock 1,z").
bool parseCordList(const std::string& option, const std::string& text, int count,
                   const std::set<int>& edited, bool allow_edited, std::set<int>& out,
                   std::string& problem) {
  out.clear();
  if (text == "all") {
    for (int i = 0; i < count; ++i) out.insert(i);
    return true;
  }
  if (allow_edited && text == "edited") {
    out = edited;
    return true;
  }
  std::istringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    char* end = nullptr;
    const long index = std::strtol(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0' || index < 0 || index >= count) {
      problem = option + ": \"" + item + "\" is not a cord index 0.." + std::to_string(count - 1) +
                (allow_edited ? ", \"edited\" or \"all\"" : " or \"all\"");
      return false;
    }
    if (!out.insert(static_cast<int>(index)).second) {
      // As across options ("--cord 1=0.8 --cord 1=1.2" is refused): one cord, one request.
      problem = option + ": cord " + item + " appears twice in the list";
      return false;
    }
  }
  if (out.empty()) {
    problem = option + ": expected cord indices";
    return false;
  }
  return true;
}

// "DX,DY,DZ": exactly three finite numbers.
bool parseOffset(const std::string& text, Eigen::Vector3d& offset) {
  std::vector<std::string> fields;
  std::istringstream in(text);
  for (std::string field; std::getline(in, field, ',');) fields.push_back(field);
  if (fields.size() != 3) return false;
  for (int k = 0; k < 3; ++k) {
    // Blanks around a number are the user's spacing ("1, 2, 3"), not part of it.
    if (!parseDecimal(trimmed(fields[k]), offset(k))) return false;
  }
  return true;
}

std::string namesOf(const std::set<std::string>& names) {
  std::string text;
  for (const std::string& n : names) text += (text.empty() ? "" : ", ") + n;
  return text;
}

// "--cord 1=0.8: cord 1 is already scaled by --cord 1=1.2: give each cord once". Within one
// option the last of two requests for the same thing used to win without a word; across
// options (--all, then --group, ...) the more specific one wins by design (docs/fitting.md).
std::string givenTwice(const std::string& request, const std::string& what, const char* done,
                       const std::string& earlier, const std::string& advice) {
  return request + ": " + what + " is already " + done + " by " + earlier + ": " + advice;
}

// One scaling request, resolved to cord indices.
struct ScaleRequest {
  std::string what;  // "--group anterior/anterolateral=0.9"
  std::vector<int> cords;
  double scale = 1.0;
};

}  // namespace

int runEditCords(const EditCordsOptions& options) {
  if (options.all_scale.empty() && options.group_scales.empty() && options.segment_scales.empty() &&
      options.cord_scales.empty() && options.tip_moves.empty() && options.lock.empty() &&
      options.unlock.empty()) {
    return usage(
        "nothing to do: give --all, --group, --segment, --cord, --move-tip, --lock or --unlock");
  }
  const auto valve_case = loadCaseOrReport(options.case_dir);
  if (!valve_case) return kExitBadInput;
  auto cords = resolveCords(*valve_case, options.cords_file);
  if (!cords) return kExitBadInput;
  CordSet set = *cords;
  const CordSet before = set;
  const ValveMesh& mesh = valve_case->mesh;
  const int count = static_cast<int>(set.cords.size());
  if (count == 0)
    return usage(noCordsProblem(*valve_case, options.case_dir, options.cords_file, "--cords") +
                 ": nothing to edit");

  // Each cord's group (leaflet/tip) and Carpentier segment (open-state position of its vertex).
  const Eigen::VectorXi vertex_segments = openStateSegments(mesh);
  std::vector<std::string> group(count), segment(count);
  std::set<std::string> groups, segments;
  for (int i = 0; i < count; ++i) {
    const Cord& cord = set.cords[i];
    group[i] = groupName(cord, mesh.leaflet, mesh.leaflet_names, set.tips);
    const int id = vertex_segments(cord.vertex);
    segment[i] = id >= 0 ? segmentName(mesh.leaflet_names, id) : "?";
    groups.insert(group[i]);
    segments.insert(segment[i]);
  }

  // Parse and resolve everything before changing anything.
  std::vector<ScaleRequest> requests;
  std::string problem;
  if (!options.all_scale.empty()) {
    ScaleRequest r{"--all " + options.all_scale, {}, 1.0};
    if (!parseScale(options.all_scale, r.scale)) {
      return usage("--all " + options.all_scale + ": the scale must be a number in (0, " +
                   std::to_string(static_cast<int>(kMaxScale)) + "]");
    }
    for (int i = 0; i < count; ++i) r.cords.push_back(i);
    requests.push_back(r);
  }
  const auto byName = [&](const std::string& option, const std::vector<std::string>& items,
                          const std::vector<std::string>& names_of_cords,
                          const std::set<std::string>& names, const char* kind) {
    std::map<std::string, std::string> scaled_by;  // name -> the request that scales it
    for (const std::string& item : items) {
      ScaleRequest r{option + " " + item, {}, 1.0};
      std::string name;
      if (!splitAssignment(option, item, name, r.scale, problem)) return false;
      // Segment and leaflet names are the user's to type: "p2" is P2 when no other name
      // differs from it in case alone.
      if (!names.count(name)) {
        std::vector<std::string> alike;
        for (const std::string& known : names)
          if (asciiLowercase(known) == asciiLowercase(name)) alike.push_back(known);
        if (alike.size() == 1) name = alike.front();
      }
      if (!names.count(name)) {
        problem = option + " " + item + ": no cord in " + kind + " \"" + name + "\" (the cords' " +
                  kind + "s: " + namesOf(names) + ")";
        return false;
      }
      if (const auto [earlier, first] = scaled_by.emplace(name, r.what); !first) {
        problem = givenTwice(r.what, std::string(kind) + " \"" + name + "\"", "scaled",
                             earlier->second, "give each " + std::string(kind) + " once");
        return false;
      }
      for (int i = 0; i < count; ++i)
        if (names_of_cords[i] == name) r.cords.push_back(i);
      requests.push_back(r);
    }
    return true;
  };
  if (!byName("--group", options.group_scales, group, groups, "group") ||
      !byName("--segment", options.segment_scales, segment, segments, "segment")) {
    return usage(problem);
  }
  std::map<int, std::string> cord_scaled_by;  // cord -> the --cord that scales it
  for (const std::string& item : options.cord_scales) {
    ScaleRequest r{"--cord " + item, {}, 1.0};
    std::string name;
    std::set<int> index;
    if (!splitAssignment("--cord", item, name, r.scale, problem) ||
        !parseCordList("--cord " + item, name, count, {}, false, index, problem)) {
      return usage(problem);
    }
    for (const int i : index) {
      if (const auto [earlier, first] = cord_scaled_by.emplace(i, r.what); !first)
        return usage(givenTwice(r.what, "cord " + std::to_string(i), "scaled", earlier->second,
                                "give each cord once"));
    }
    r.cords.assign(index.begin(), index.end());
    requests.push_back(r);
  }
  std::vector<std::pair<int, Eigen::Vector3d>> moves;  // tip index, offset
  std::map<int, std::string> tip_moved_by;             // tip index -> the --move-tip moving it
  std::set<std::string> tip_names;
  for (const PmTip& tip : set.tips) tip_names.insert(tip.name);
  for (const std::string& item : options.tip_moves) {
    const std::size_t eq = item.rfind('=');
    int tip = -1;
    for (std::size_t t = 0; eq != std::string::npos && t < set.tips.size(); ++t) {
      if (set.tips[t].name == item.substr(0, eq)) tip = static_cast<int>(t);
    }
    if (tip < 0) {
      return usage("--move-tip " + item + ": expected NAME=DX,DY,DZ with NAME one of the tips (" +
                   namesOf(tip_names) + ")");
    }
    Eigen::Vector3d offset;
    if (!parseOffset(item.substr(eq + 1), offset)) {
      return usage("--move-tip " + item +
                   ": the offset must be three finite numbers DX,DY,DZ (mm)");
    }
    // Offsets of one tip would add up, and each line printed would show the sum.
    if (const auto [earlier, first] = tip_moved_by.emplace(tip, "--move-tip " + item); !first)
      return usage(givenTwice("--move-tip " + item, "tip \"" + set.tips[tip].name + "\"", "moved",
                              earlier->second, "give one offset per tip"));
    moves.emplace_back(tip, offset);
  }
  std::set<int> unlock;
  if (!options.unlock.empty() && !parseCordList("--unlock " + options.unlock, options.unlock, count,
                                                {}, false, unlock, problem)) {
    return usage(problem);
  }
  std::set<int> lock;  // checked now, resolved after the scaling ("edited")
  if (!options.lock.empty() &&
      !parseCordList("--lock " + options.lock, options.lock, count, {}, true, lock, problem)) {
    return usage(problem);
  }

  // Apply: unlock, scale (in the order given), lock.
  for (const int i : unlock) set.cords[i].locked = false;
  std::set<int> edited;
  int left_locked = 0;
  for (const ScaleRequest& r : requests) {
    int changed = 0;
    for (const int i : r.cords) {
      if (scaleCord(set, i, r.scale) == 1) {
        ++changed;
        edited.insert(i);
      }
    }
    const int locked = static_cast<int>(r.cords.size()) - changed;
    left_locked += locked;
    std::printf("  %-40s %3d %s scaled", r.what.c_str(), changed, nounFor(changed, "cord").c_str());
    if (locked > 0) std::printf(", %d locked left alone", locked);
    std::printf("\n");
  }
  // A scaled rest length must be one a cord set holds (cordset_io.h); written, the set would
  // be refused by every command that reads it (a scale of 0.001 gave 0.02 mm cords).
  for (const int i : edited) {
    const Cord& cord = set.cords[i];
    if (cord.rest_length >= kMinCordRestLengthMm && cord.rest_length <= kMaxCordRestLengthMm)
      continue;
    std::ostringstream problem;
    problem << "cord " << i << ": the scalings give it a rest length of " << cord.rest_length
            << " mm (its seed " << cord.seed_rest_length << " mm times " << cord.scale()
            << "); a cord set holds " << kMinCordRestLengthMm << " to " << kMaxCordRestLengthMm
            << " mm";
    return usage(problem.str());
  }
  for (const auto& [tip, offset] : moves) {
    set.tips[tip].position += offset;
    if (set.tips[tip].closed_position) *set.tips[tip].closed_position += offset;
  }
  // A moved tip must stay within reach of the valve and below the annulus, as a case's tips
  // must (case_extent.h); otherwise every command reading the set would refuse it.
  Diagnostics far_tips;
  if (!checkTipPlacement(mesh, set.tips, "edit-cords: --move-tip", far_tips)) {
    far_tips.print(std::cerr);
    return kExitBadInput;
  }
  for (const auto& [tip, offset] : moves) {
    std::printf("  --move-tip %-29s moved by (%.2f, %.2f, %.2f) mm to (%.2f, %.2f, %.2f)\n",
                set.tips[tip].name.c_str(), offset.x(), offset.y(), offset.z(),
                set.tips[tip].position.x(), set.tips[tip].position.y(), set.tips[tip].position.z());
  }
  if (!options.lock.empty()) {
    parseCordList("--lock " + options.lock, options.lock, count, edited, true, lock, problem);
    for (const int i : lock) set.cords[i].locked = true;
  }

  writeCordSet(options.out_file, set, &mesh);
  forgetPublished(options.out_file);  // now the user's file (staged_output.h)

  const auto locked_in_all = std::count_if(set.cords.begin(), set.cords.end(),
                                           [](const Cord& cord) { return cord.locked; });
  std::printf(
      "edit-cords: %s, %zu edited, %zu locked by --lock, %zu unlocked, %ld locked in "
      "all -> %s\n",
      counted(count, "cord").c_str(), edited.size(), lock.size(), unlock.size(),
      static_cast<long>(locked_in_all), options.out_file.c_str());
  bool any_changed = false;
  for (int i = 0; i < count; ++i) {
    any_changed |= before.cords[i].rest_length != set.cords[i].rest_length ||
                   before.cords[i].locked != set.cords[i].locked;
  }
  if (any_changed) {
    std::printf("  %5s  %-30s %-4s %-9s %9s %18s %7s  %-9s %s\n", "cord", "group (leaflet/tip)",
                "seg", "kind", "seed (mm)", "rest (mm) before>after", "scale", "provenance",
                "locked");
  }
  std::vector<int> outside_bounds;  // unlocked cords the fit would start clamped
  for (int i = 0; i < count; ++i) {
    const Cord& a = before.cords[i];
    const Cord& b = set.cords[i];
    const double scale =
        inverse::snapToBoundWithinRounding(b.scale(), kFitScaleLower, kFitScaleUpper);
    if (!b.locked && (scale < kFitScaleLower || scale > kFitScaleUpper))
      outside_bounds.push_back(i);
    if (a.rest_length == b.rest_length && a.locked == b.locked) continue;
    std::printf("  %5d  %-30s %-4s %-9s %9.2f %8.2f > %8.2f %7.3f  %-9s %s\n", i, group[i].c_str(),
                segment[i].c_str(), toString(b.kind), b.seed_rest_length, a.rest_length,
                b.rest_length, b.scale(), toString(b.provenance), b.locked ? "yes" : "no");
  }
  if (left_locked > 0) {
    std::printf(
        "  (%s left alone by the scalings; --unlock them first to change "
        "them)\n",
        counted(left_locked, "locked cord").c_str());
  }
  if (!any_changed && !requests.empty() && moves.empty())
    printWarning("edit-cords: nothing changed: %s\n",
                 edited.empty() ? "every cord the scalings name is locked"
                                : "the scalings leave every rest length as it was (scale 1)");
  if (!outside_bounds.empty()) {
    std::string listed;
    for (std::size_t k = 0; k < outside_bounds.size() && k < 12; ++k)
      listed += (k == 0 ? "" : ",") + std::to_string(outside_bounds[k]);
    if (outside_bounds.size() > 12) listed += ",...";
    printNote(
        "%zu unlocked cord%s (%s) %s a scale outside the fit's default bounds [%.1f, "
        "%.1f]; `chordfit fit --seed-cords` starts them clamped (lock them to keep them, or "
        "widen --scale-bounds)\n",
        outside_bounds.size(), outside_bounds.size() == 1 ? "" : "s", listed.c_str(),
        outside_bounds.size() == 1 ? "has" : "have", kFitScaleLower, kFitScaleUpper);
  }
  return kExitOk;
}

}  // namespace chordfit::cli
