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

// Each cord's group (leaflet/tip) and Carpentier segment (open-state position of its vertex),
// and every name some cord has: what --group and --segment name, and the table's columns.
struct CordNames {
  std::vector<std::string> group, segment;  // one per cord
  std::set<std::string> groups, segments;
};

CordNames nameCords(const ValveMesh& mesh, const CordSet& set) {
  const int count = static_cast<int>(set.cords.size());
  const Eigen::VectorXi vertex_segments = openStateSegments(mesh);
  CordNames names;
  names.group.resize(count);
  names.segment.resize(count);
  for (int i = 0; i < count; ++i) {
    const Cord& cord = set.cords[i];
    names.group[i] = groupName(cord, mesh.leaflet, mesh.leaflet_names, set.tips);
    const int id = vertex_segments(cord.vertex);
    names.segment[i] = id >= 0 ? segmentName(mesh.leaflet_names, id) : "?";
    names.groups.insert(names.group[i]);
    names.segments.insert(names.segment[i]);
  }
  return names;
}

// One --move-tip, resolved to the tip's index.
struct TipMove {
  int tip = -1;
  Eigen::Vector3d offset;
};

// Everything the options ask, parsed and resolved against the cord set before anything
// changes. Not --lock: it is checked with the rest (parseLockLists) but resolved after the
// scalings, which say what its "edited" is (lockCords).
struct EditRequests {
  std::vector<ScaleRequest> scalings;  // --all, --group, --segment, --cord: the order applied
  std::vector<TipMove> tip_moves;
  std::set<int> unlock;
  bool lock_edited = false;  // --lock edited: the cords the scalings change
};

bool asksForNothing(const EditCordsOptions& options) {
  return options.all_scale.empty() && options.group_scales.empty() &&
         options.segment_scales.empty() && options.cord_scales.empty() &&
         options.tip_moves.empty() && options.lock.empty() && options.unlock.empty();
}

// --all S (none when `text` is empty): every one of the `count` cords. False with `problem`
// set otherwise.
bool parseAllScale(const std::string& text, int count, std::vector<ScaleRequest>& scalings,
                   std::string& problem) {
  if (text.empty()) return true;
  ScaleRequest r{"--all " + text, {}, 1.0};
  if (!parseScale(text, r.scale)) {
    problem = "--all " + text + ": the scale must be a number in (0, " +
              std::to_string(static_cast<int>(kMaxScale)) + "]";
    return false;
  }
  for (int i = 0; i < count; ++i) r.cords.push_back(i);
  scalings.push_back(r);
  return true;
}

// Segment and leaflet names are the user's to type: "p2" is P2 when no other name differs
// from it in case alone. Otherwise `name` as typed.
std::string knownSpelling(const std::string& name, const std::set<std::string>& names) {
  if (names.count(name)) return name;
  std::vector<std::string> alike;
  for (const std::string& known : names)
    if (asciiLowercase(known) == asciiLowercase(name)) alike.push_back(known);
  return alike.size() == 1 ? alike.front() : name;
}

// `option` ("--group") NAME=S items, each scaling the cords whose name in `names_of_cords`
// (one per cord) is NAME, one of `names`; `kind` ("group") is what a NAME is. Each NAME once.
// False with `problem` set otherwise.
bool parseNamedScales(const std::string& option, const std::vector<std::string>& items,
                      const std::vector<std::string>& names_of_cords,
                      const std::set<std::string>& names, const char* kind,
                      std::vector<ScaleRequest>& scalings, std::string& problem) {
  const int count = static_cast<int>(names_of_cords.size());
  std::map<std::string, std::string> scaled_by;  // name -> the request that scales it
  for (const std::string& item : items) {
    ScaleRequest r{option + " " + item, {}, 1.0};
    std::string name;
    if (!splitAssignment(option, item, name, r.scale, problem)) return false;
    name = knownSpelling(name, names);
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
    scalings.push_back(r);
  }
  return true;
}

// --cord K=S, K,K=S or all=S items over `count` cords, each cord once. False with `problem`
// set otherwise.
bool parseCordScales(const std::vector<std::string>& items, int count,
                     std::vector<ScaleRequest>& scalings, std::string& problem) {
  std::map<int, std::string> cord_scaled_by;  // cord -> the --cord that scales it
  for (const std::string& item : items) {
    ScaleRequest r{"--cord " + item, {}, 1.0};
    std::string name;
    std::set<int> index;
    if (!splitAssignment("--cord", item, name, r.scale, problem) ||
        !parseCordList("--cord " + item, name, count, {}, false, index, problem)) {
      return false;
    }
    for (const int i : index) {
      if (const auto [earlier, first] = cord_scaled_by.emplace(i, r.what); !first) {
        problem = givenTwice(r.what, "cord " + std::to_string(i), "scaled", earlier->second,
                             "give each cord once");
        return false;
      }
    }
    r.cords.assign(index.begin(), index.end());
    scalings.push_back(r);
  }
  return true;
}

// --move-tip NAME=DX,DY,DZ items, NAME one of `tips`, each tip once. False with `problem` set
// otherwise.
bool parseTipMoves(const std::vector<std::string>& items, const std::vector<PmTip>& tips,
                   std::vector<TipMove>& moves, std::string& problem) {
  std::map<int, std::string> tip_moved_by;  // tip index -> the --move-tip moving it
  std::set<std::string> tip_names;
  for (const PmTip& tip : tips) tip_names.insert(tip.name);
  for (const std::string& item : items) {
    const std::size_t eq = item.rfind('=');
    int tip = -1;
    for (std::size_t t = 0; eq != std::string::npos && t < tips.size(); ++t) {
      if (tips[t].name == item.substr(0, eq)) tip = static_cast<int>(t);
    }
    if (tip < 0) {
      problem = "--move-tip " + item + ": expected NAME=DX,DY,DZ with NAME one of the tips (" +
                namesOf(tip_names) + ")";
      return false;
    }
    Eigen::Vector3d offset;
    if (!parseOffset(item.substr(eq + 1), offset)) {
      problem = "--move-tip " + item + ": the offset must be three finite numbers DX,DY,DZ (mm)";
      return false;
    }
    // Offsets of one tip would add up, and each line printed would show the sum.
    if (const auto [earlier, first] = tip_moved_by.emplace(tip, "--move-tip " + item); !first) {
      problem = givenTwice("--move-tip " + item, "tip \"" + tips[tip].name + "\"", "moved",
                           earlier->second, "give one offset per tip");
      return false;
    }
    moves.push_back({tip, offset});
  }
  return true;
}

// --unlock, then --lock, which is only checked: lockCords resolves it once the scalings have
// made their edits. False with `problem` set on a bad list.
bool parseLockLists(const EditCordsOptions& options, int count, std::set<int>& unlock,
                    std::string& problem) {
  if (!options.unlock.empty() && !parseCordList("--unlock " + options.unlock, options.unlock, count,
                                                {}, false, unlock, problem)) {
    return false;
  }
  std::set<int> lock;
  return options.lock.empty() ||
         parseCordList("--lock " + options.lock, options.lock, count, {}, true, lock, problem);
}

// Every request of `options` against `set`, checked in the order --all, --group, --segment,
// --cord, --move-tip, --unlock, --lock: the first problem is the one reported. False with
// `problem` set otherwise.
bool parseRequests(const EditCordsOptions& options, const CordSet& set, const CordNames& names,
                   EditRequests& requests, std::string& problem) {
  const int count = static_cast<int>(set.cords.size());
  requests.lock_edited = options.lock == "edited";
  return parseAllScale(options.all_scale, count, requests.scalings, problem) &&
         parseNamedScales("--group", options.group_scales, names.group, names.groups, "group",
                          requests.scalings, problem) &&
         parseNamedScales("--segment", options.segment_scales, names.segment, names.segments,
                          "segment", requests.scalings, problem) &&
         parseCordScales(options.cord_scales, count, requests.scalings, problem) &&
         parseTipMoves(options.tip_moves, set.tips, requests.tip_moves, problem) &&
         parseLockLists(options, count, requests.unlock, problem);
}

// What the scalings did: the cords they changed, and how many times they named a locked cord.
struct ScalingOutcome {
  std::set<int> edited;
  int left_locked = 0;
  std::string lines;  // one per scaling, printed once every edit is known to be valid
};

// Applies the scalings in the order given, so that the more specific one wins, with a line
// for each. scaleCord leaves locked cords alone.
ScalingOutcome scaleCords(const std::vector<ScaleRequest>& scalings, CordSet& set) {
  ScalingOutcome outcome;
  for (const ScaleRequest& r : scalings) {
    int changed = 0;
    for (const int i : r.cords) {
      if (scaleCord(set, i, r.scale) == 1) {
        ++changed;
        outcome.edited.insert(i);
      }
    }
    const int locked = static_cast<int>(r.cords.size()) - changed;
    outcome.left_locked += locked;
    char count[64];
    std::snprintf(count, sizeof count, " %3d %s scaled", changed, nounFor(changed, "cord").c_str());
    // The request as typed, padded to 40 columns and never cut (a long --cord list).
    outcome.lines +=
        "  " + r.what + std::string(r.what.size() < 40 ? 40 - r.what.size() : 0, ' ') + count;
    if (locked > 0) outcome.lines += ", " + std::to_string(locked) + " locked left alone";
    outcome.lines += "\n";
  }
  return outcome;
}

// The first `edited` cord whose rest length a cord set cannot hold, named with how the
// scalings got there; "" when there is none. A scaled rest length must be one a cord set holds
// (cordset_io.h); written, the set would be refused by every command that reads it (a scale
// of 0.001 gave 0.02 mm cords).
std::string restLengthProblem(const CordSet& set, const std::set<int>& edited) {
  for (const int i : edited) {
    const Cord& cord = set.cords[i];
    if (cord.rest_length >= kMinCordRestLengthMm && cord.rest_length <= kMaxCordRestLengthMm)
      continue;
    std::ostringstream problem;
    problem << "cord " << i << ": the scalings give it a rest length of " << cord.rest_length
            << " mm (its seed " << cord.seed_rest_length << " mm times " << cord.scale()
            << "); a cord set holds " << kMinCordRestLengthMm << " to " << kMaxCordRestLengthMm
            << " mm";
    return problem.str();
  }
  return "";
}

// Moves each tip, its open and (when present) closed position. False, with the problems
// printed, when a tip of the set is out of place afterwards.
bool moveTips(const ValveMesh& mesh, const std::vector<TipMove>& moves, CordSet& set) {
  for (const auto& [tip, offset] : moves) {
    set.tips[tip].position += offset;
    if (set.tips[tip].closed_position) *set.tips[tip].closed_position += offset;
  }
  if (moves.empty()) return true;  // the set's tips were checked when it was read
  // A moved tip must stay within reach of the valve and below the annulus, as a case's tips
  // must (case_extent.h); otherwise every command reading the set would refuse it.
  Diagnostics far_tips;
  if (!checkTipPlacement(mesh, set.tips, "edit-cords: --move-tip", far_tips)) {
    far_tips.print(std::cerr);
    return false;
  }
  return true;
}

// A line per moved tip: by how much and where it went.
void printTipMoves(const std::vector<TipMove>& moves, const CordSet& set) {
  for (const auto& [tip, offset] : moves) {
    const Eigen::Vector3d& at = set.tips[tip].position;
    std::printf("  --move-tip %-29s moved by (%.2f, %.2f, %.2f) mm to (%.2f, %.2f, %.2f)\n",
                set.tips[tip].name.c_str(), offset.x(), offset.y(), offset.z(), at.x(), at.y(),
                at.z());
  }
}

// Locks the cords of --lock `list` (checked by parseLockLists), its "edited" being the cords
// the scalings changed. Returns the cords it names (none for an empty list).
std::set<int> lockCords(const std::string& list, const std::set<int>& edited, CordSet& set) {
  std::set<int> lock;
  if (list.empty()) return lock;
  std::string problem;  // none: the list was checked before the edits
  parseCordList("--lock " + list, list, static_cast<int>(set.cords.size()), edited, true, lock,
                problem);
  for (const int i : lock) set.cords[i].locked = true;
  return lock;
}

// A change the table shows and the nothing-changed warning looks for: the rest length or the
// lock (a scale of 1 only makes the cord manual).
bool cordChanged(const Cord& before, const Cord& after) {
  return before.rest_length != after.rest_length || before.locked != after.locked;
}

bool anyCordChanged(const CordSet& before, const CordSet& after) {
  for (std::size_t i = 0; i < before.cords.size(); ++i)
    if (cordChanged(before.cords[i], after.cords[i])) return true;
  return false;
}

// A table of the cords whose rest length or lock the edit changed; nothing when none.
void printChangedCords(const CordSet& before, const CordSet& after, const CordNames& names) {
  if (!anyCordChanged(before, after)) return;
  std::printf("  %5s  %-30s %-4s %-9s %9s %18s %7s  %-9s %s\n", "cord", "group (leaflet/tip)",
              "seg", "kind", "seed (mm)", "rest (mm) before>after", "scale", "provenance",
              "locked");
  const int count = static_cast<int>(after.cords.size());
  for (int i = 0; i < count; ++i) {
    const Cord& a = before.cords[i];
    const Cord& b = after.cords[i];
    if (!cordChanged(a, b)) continue;
    std::printf("  %5d  %-30s %-4s %-9s %9.2f %8.2f > %8.2f %7.3f  %-9s %s\n", i,
                names.group[i].c_str(), names.segment[i].c_str(), toString(b.kind),
                b.seed_rest_length, a.rest_length, b.rest_length, b.scale(), toString(b.provenance),
                b.locked ? "yes" : "no");
  }
}

// The unlocked cords the fit would start clamped: their scale lies outside its default bounds.
std::vector<int> unlockedOutsideFitBounds(const CordSet& set) {
  std::vector<int> outside;
  const int count = static_cast<int>(set.cords.size());
  for (int i = 0; i < count; ++i) {
    const Cord& cord = set.cords[i];
    const double scale =
        inverse::snapToBoundWithinRounding(cord.scale(), kFitScaleLower, kFitScaleUpper);
    if (!cord.locked && (scale < kFitScaleLower || scale > kFitScaleUpper)) outside.push_back(i);
  }
  return outside;
}

// A note naming them (the first 12) when there are any.
void noteScalesOutsideFitBounds(const std::vector<int>& outside_bounds) {
  if (outside_bounds.empty()) return;
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

// What the edit did, written to `out_file` (`locked`: the cords --lock locked): a summary line
// and the table of changed cords on stdout, then on stderr a warning when the scalings changed
// nothing and a note on scales the fit would clamp.
void reportEdits(const std::string& out_file, const CordSet& before, const CordSet& after,
                 const CordNames& names, const EditRequests& requests, const ScalingOutcome& scaled,
                 const std::set<int>& locked) {
  // Locks counted as they changed: --unlock all on a set with nothing locked unlocks none.
  int newly_locked = 0, newly_unlocked = 0, locked_in_all = 0, made_manual = 0;
  for (std::size_t i = 0; i < after.cords.size(); ++i) {
    const Cord& a = before.cords[i];
    const Cord& b = after.cords[i];
    newly_locked += !a.locked && b.locked;
    newly_unlocked += a.locked && !b.locked;
    locked_in_all += b.locked;
    made_manual += a.provenance != b.provenance;
  }
  std::printf("edit-cords: %s, %zu edited, %d locked, %d unlocked, %d locked in all -> %s\n",
              counted(static_cast<int>(after.cords.size()), "cord").c_str(), scaled.edited.size(),
              newly_locked, newly_unlocked, locked_in_all, out_file.c_str());
  printChangedCords(before, after, names);
  if (scaled.left_locked > 0) {
    std::printf(
        "  (%s left alone by the scalings; --unlock them first to change "
        "them)\n",
        counted(scaled.left_locked, "locked cord").c_str());
  }
  if (!anyCordChanged(before, after) && !requests.scalings.empty() && requests.tip_moves.empty()) {
    if (scaled.edited.empty())
      printWarning("edit-cords: nothing changed: every cord the scalings name is locked\n");
    else if (made_manual == 0)
      printWarning(
          "edit-cords: nothing changed: the scalings leave every rest length as it was "
          "(scale 1)\n");
    else
      printWarning("edit-cords: no rest length changed (scale 1); %s now manual\n",
                   counted(made_manual, "cord").c_str());
  }
  if (locked.empty() && requests.lock_edited)
    printWarning("edit-cords: --lock edited: no cord was edited, so none was locked\n");
  noteScalesOutsideFitBounds(unlockedOutsideFitBounds(after));
}

}  // namespace

int runEditCords(const EditCordsOptions& options) {
  if (asksForNothing(options)) {
    return usage(
        "nothing to do: give --all, --group, --segment, --cord, --move-tip, --lock or --unlock");
  }
  const auto valve_case = loadCaseOrReport(options.case_dir);
  if (!valve_case) return kExitBadInput;
  const auto before = resolveCords(*valve_case, options.cords_file, "edit-cords: --cords");
  if (!before) return kExitBadInput;
  if (before->cords.empty())
    return usage(noCordsProblem(*valve_case, options.case_dir, options.cords_file, "--cords") +
                 ": nothing to edit");
  const ValveMesh& mesh = valve_case->mesh;
  const CordNames names = nameCords(mesh, *before);

  // Parse and resolve everything before changing anything.
  EditRequests requests;
  if (std::string problem; !parseRequests(options, *before, names, requests, problem))
    return usage(problem);

  // Apply: unlock, scale (in the order given), lock.
  CordSet set = *before;
  for (const int i : requests.unlock) set.cords[i].locked = false;
  const ScalingOutcome scaled = scaleCords(requests.scalings, set);
  if (const std::string problem = restLengthProblem(set, scaled.edited); !problem.empty())
    return usage(problem);
  if (!moveTips(mesh, requests.tip_moves, set)) return kExitBadInput;
  // Printed once every change is known to be valid: a refused edit prints only its error.
  std::fputs(scaled.lines.c_str(), stdout);
  printTipMoves(requests.tip_moves, set);
  const std::set<int> locked = lockCords(options.lock, scaled.edited, set);

  writeCordSet(options.out_file, set, &mesh);
  forgetPublished(options.out_file);  // now the user's file (staged_output.h)
  reportEdits(options.out_file, *before, set, names, requests, scaled, locked);
  return kExitOk;
}

}  // namespace chordfit::cli
