// chordfit sweep-cord: scan one cord's rest-length scale and measure how smooth the forward
// map (scale -> closed state) is. DESIGN §7: the map must be reproducible to far below the
// finite-difference step, or the Jacobian is noise.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/annulus_plane.h"
#include "core/atomic_file.h"
#include "core/carpentier.h"
#include "core/case_io.h"
#include "core/cgal_backend.h"
#include "core/closure_model.h"
#include "core/counted.h"
#include "core/forward_map_noise.h"
#include "core/metrics.h"
#include "core/parallel_for.h"
#include "core/svg_line_plot.h"
#include "tools/command_support.h"
#include "tools/commands.h"
#include "tools/in_order_progress.h"
#include "tools/staged_output.h"

namespace chordfit::cli {

namespace {

// The signal a finite-difference step of this relative size sees (issue: 0.5 %).
constexpr double kReferenceStep = 0.005;
constexpr int kP2 = 1 * 3 + 1;  // posterior leaflet (label 1), middle third
// The most scales one sweep runs: each is a full closure (seconds to minutes), and 2,001 is
// already a step of 1e-4 over +-0.1 or 5e-4 over the widest range; more is a mistyped
// --step rather than a plan (1e-9 used to die in std::bad_alloc, 1e-6 started 100,001
// closures). The widest --window is the one that this many scales can still fill.
constexpr int kMaxScales = 2001;
constexpr int kMaxWindow = (kMaxScales - 1) / 2;

// The P2 primary cord whose vertex lies nearest the posterior midline (angle pi).
int defaultP2PrimaryCord(const ValveCase& c, const CordSet& cords) {
  const AnnulusFrame frame = openAnnulusFrame(c.mesh);
  Eigen::MatrixXd ring(c.mesh.annulus.size(), 3);
  for (Eigen::Index i = 0; i < ring.rows(); ++i) ring.row(i) = c.mesh.V.row(c.mesh.annulus(i));
  const SegmentMap segments = buildSegmentMap(ring, c.mesh, frame);
  int best = -1;
  double best_offset = 1e9;
  for (std::size_t i = 0; i < cords.cords.size(); ++i) {
    const Cord& cord = cords.cords[i];
    const Eigen::Vector3d p = insertionPosition(cord, c.mesh.V);
    if (cord.kind != CordKind::kPrimary ||
        segmentOf(segments, p, c.mesh.leaflet(cord.vertex)) != kP2) {
      continue;
    }
    const double offset = std::abs(std::remainder(annulusAngle(frame, p) - M_PI, 2 * M_PI));
    if (offset < best_offset) {
      best_offset = offset;
      best = static_cast<int>(i);
    }
  }
  return best;
}

struct SweepPoint {
  double scale = 1.0;
  double mean_deviation = NAN;
  Eigen::Vector3d vertex = Eigen::Vector3d::Constant(NAN);
  double height = NAN;  // vertex height above the closed annulus plane
  bool converged = false;
  int steps = 0;
  // Triangle pairs of the closed leaflets passing through each other (0 expected): a closure
  // with very short cords can pull the sheets through; simulate reports it, the sweep did not.
  int self_intersections = 0;
  std::string error;
  bool diverged = false;  // the error is a divergence, not invalid input
};

std::string sweepCsv(const std::vector<SweepPoint>& points) {
  std::ostringstream csv;
  csv.precision(12);
  csv << "scale,mean_deviation_mm,vertex_x_mm,vertex_y_mm,vertex_z_mm,vertex_height_mm,"
         "converged,steps,self_intersections\n";
  for (const SweepPoint& p : points) {
    csv << p.scale << "," << p.mean_deviation << "," << p.vertex.x() << "," << p.vertex.y() << ","
        << p.vertex.z() << "," << p.height << "," << (p.converged ? 1 : 0) << "," << p.steps << ","
        << p.self_intersections << "\n";
  }
  return csv.str();
}

// The verdict of issue 3 item 6, "noise far below the change a 0.5 % step causes": at least
// ten times below it. A map that moves less than kFlatMm over a 0.5 % step is flat (a cord
// slack over the whole range moves nothing): no signal to compare the noise with.
constexpr double kSmoothSignalToNoise = 10.0;
constexpr double kFlatMm = 1e-9;

nlohmann::json noiseJson(const MapNoise& noise, const std::vector<double>& s,
                         const std::vector<double>& q) {
  const double signal = std::abs(noise.slope) * kReferenceStep;
  const double ratio = noise.max > 0 ? signal / noise.max : INFINITY;
  const bool flat = signal < kFlatMm;
  const double turns = turningScale(s, q, noise.max);
  nlohmann::json j = {{"noise_rms", noise.rms},
                      {"noise_max", noise.max},
                      {"slope_per_unit_scale", noise.slope},
                      {"change_over_0.5_percent", signal},
                      {"signal_to_noise", ratio},
                      {"flat", flat},
                      {"smooth", !flat && ratio >= kSmoothSignalToNoise}};
  j["turns_at_scale"] = std::isfinite(turns) ? nlohmann::json(turns) : nlohmann::json(nullptr);
  return j;
}

// "smooth (...)", "NOT smooth (...)" or "flat (...)" for the printed line.
std::string verdictText(const nlohmann::json& n) {
  if (n["flat"].get<bool>())
    return "flat: it does not move over the range (a cord slack throughout?)";
  if (n["smooth"].get<bool>()) return "smooth (signal/noise >= 10)";
  std::string text = "NOT smooth (signal/noise < 10)";
  if (n["turns_at_scale"].is_number()) {
    char note[160];
    std::snprintf(note, sizeof note,
                  "; the curve turns near scale %.4g, where a step changes it little: sweep "
                  "away from there before reading this as noise",
                  n["turns_at_scale"].get<double>());
    text += note;
  }
  return text;
}

// The scales a sweep closes at: 1 + (i - half) step for i in [0, count), centred on the cord as
// given.
struct ScaleGrid {
  int count = 0;
  int half = 0;
  double step = 0.0;
  double scale(int i) const { return 1.0 + (i - half) * step; }
};

// --range and --step; false with the problem printed otherwise.
bool rangeAndStepUsable(const SweepCordOptions& options) {
  // Below 0.5 the scales 1 - range stay at half the cord's length or more.
  if (!(options.range > 0.0 && options.range < 0.5)) {
    std::cerr << "error: sweep-cord: --range: must be in (0, 0.5), got " << options.range << "\n";
    return false;
  }
  if (!(options.step > 0.0) || options.step > options.range) {
    std::cerr << "error: sweep-cord: --range/--step: --step must be in (0, --range "
              << options.range << "], got " << options.step << "\n";
    return false;
  }
  return true;
}

// --window and --cord within their bounds; false with the problem printed otherwise.
bool windowAndCordUsable(const SweepCordOptions& options) {
  // A quadratic through fewer than 5 points (window 2) leaves no residual to call noise; a
  // window wider than the most scales a sweep may have (kMaxScales) could never be filled;
  // --cord -1 is the default (the P2 primary cord, see defaultP2PrimaryCord). --threads is
  // checked where it is read, with every command's (main.cpp).
  const struct {
    const char* option;
    int value, minimum, maximum;
  } counts[] = {{"--window", options.window, 2, kMaxWindow},
                {"--cord", options.cord, -1, std::numeric_limits<int>::max()}};
  for (const auto& count : counts)
    if (count.value < count.minimum || count.value > count.maximum) {
      std::cerr << "error: sweep-cord: " << count.option << ": must be >= " << count.minimum
                << (count.maximum < std::numeric_limits<int>::max()
                        ? " and <= " + std::to_string(count.maximum)
                        : "")
                << ", got " << count.value << "\n";
      return false;
    }
  return true;
}

// The scales --range and --step give, once every option is checked (before the case is read:
// a sweep is minutes of closures); nullopt with the problem printed otherwise. Notes a step
// that does not divide the range.
std::optional<ScaleGrid> checkedScaleGrid(const SweepCordOptions& options) {
  if (!rangeAndStepUsable(options) || !windowAndCordUsable(options)) return std::nullopt;
  // The scales 1 + k step, |k| <= half, centred on the cord as given (a grid from 1 - range
  // by step missed 1 itself and ran past 1 + range when the step did not divide the range).
  // In double: a tiny step would overflow an int (and then allocate or loop on garbage).
  const double half_steps = std::floor(options.range / options.step * (1.0 + 1e-9));
  const double scales = 2.0 * half_steps + 1.0;
  if (scales > kMaxScales) {
    std::cerr << "error: sweep-cord: --range/--step: " << options.range << "/" << options.step
              << " give " << scales << " scales, one closure each; at most " << kMaxScales
              << " (a coarser --step or a shorter --range)\n";
    return std::nullopt;
  }
  const ScaleGrid grid{static_cast<int>(scales), static_cast<int>(half_steps), options.step};
  if (std::abs(grid.half * options.step - options.range) > 1e-9 * options.range)
    printNote(
        "sweep-cord: --step %g does not divide --range %g: the scales run from %g "
        "to %g, centred on 1\n",
        options.step, options.range, 1.0 - grid.half * options.step,
        1.0 + grid.half * options.step);
  if (grid.count < 2 * options.window + 1) {  // no full window: no noise to report
    std::cerr << "error: sweep-cord: --window " << options.window << " needs at least "
              << 2 * options.window + 1 << " scales; --range/--step give " << grid.count << "\n";
    return std::nullopt;
  }
  return grid;
}

// The cord to sweep: --cord, or by default the P2 primary cord; -1 with the problem
// printed when there is no such cord (or no cord at all).
int sweptCord(const SweepCordOptions& options, const ValveCase& valve_case, const CordSet& cords) {
  if (cords.cords.empty()) {
    std::cerr << "error: sweep-cord: "
              << noCordsProblem(valve_case, options.case_dir, options.cords_file, "--cords")
              << ": nothing to sweep\n";
    return -1;
  }
  const int given = options.cord;
  const int cord = given >= 0 ? given : defaultP2PrimaryCord(valve_case, cords);
  if (given < 0 && cord < 0) {  // the default, not the user's --cord, found nothing
    std::cerr << "error: sweep-cord: the cord set has no P2 primary cord to sweep by default ("
              << counted(cords.cords.size(), "cord") << "): give --cord K\n";
    return -1;
  }
  if (cord >= static_cast<int>(cords.cords.size())) {
    std::cerr << "error: sweep-cord: --cord: no such cord " << cord << " (the set has "
              << counted(cords.cords.size(), "cord") << ": 0.." << cords.cords.size() - 1 << ")\n";
    return -1;
  }
  return cord;
}

// One cord's sweep: what each of its closures starts from and is measured against (the closed
// annulus and the tracing points, computed once when it is made).
struct CordSweep {
  const ValveCase& valve_case;
  const CordSet& cords;
  const SimulationSettings& settings;
  int cord = -1;
  ScaleGrid grid;
  ClosedAnnulus annulus = closedAnnulus(valve_case);                         // the heights' plane
  Eigen::MatrixXd tracing_points = stackTracingPoints(valve_case.tracings);  // none: no deviation

  double base() const { return cords.cords[cord].rest_length; }  // the cord's length as given
  int vertex() const { return cords.cords[cord].vertex; }
  bool hasTracings() const { return tracing_points.rows() > 0; }

  // The closure with the cord at scale i of the grid, from the open state, and its measures
  // when it succeeded.
  SweepPoint closeAt(int i) const {
    SweepPoint p;
    p.scale = grid.scale(i);
    CordSet scaled = cords;
    scaled.cords[cord].rest_length = base() * p.scale;
    const SimulationResult r = simulateClosure(valve_case, scaled, settings);
    p.error = r.error;
    p.diverged = r.diverged;
    p.converged = r.converged;
    p.steps = r.steps;
    if (r.ok()) {
      p.vertex = insertionPosition(cords.cords[cord], r.V);
      p.height = annulus.frame.plane.signedDistance(p.vertex);
      p.self_intersections = countSelfIntersections(r.V, valve_case.mesh.F);
      if (hasTracings()) {
        p.mean_deviation = pointToSurfaceDistances(r.V, valve_case.mesh.F, tracing_points).mean();
      }
    }
    return p;
  }
};

// Point i's line on stderr ("  [  3/9] scale 0.9900: height ..."), or that it failed; false
// then.
bool printProgressLine(const SweepPoint& p, int i, int count) {
  if (!p.error.empty()) {
    std::fprintf(stderr, "  [%3d/%d] scale %.4f: failed (below)\n", i + 1, count, p.scale);
    return false;  // the sweep stops at its lowest failing scale
  }
  // Without tracings there is no deviation to print ("nan mm").
  char deviation[48] = "";
  if (!std::isnan(p.mean_deviation))
    std::snprintf(deviation, sizeof deviation, ", mean deviation %.4f mm", p.mean_deviation);
  std::fprintf(stderr, "  [%3d/%d] scale %.4f: height %.4f mm%s%s\n", i + 1, count, p.scale,
               p.height, deviation, p.converged ? "" : " (not converged)");
  return true;
}

// Runs the sweep's closures on `threads` threads, with progress lines on stderr unless
// `quiet`: one point per scale. When closures fail, every point below the lowest failed one
// has run and those above it may not have (reportFailedScale reports it).
std::vector<SweepPoint> runClosures(const CordSweep& sweep, int threads, bool quiet) {
  const int count = sweep.grid.count;
  std::vector<SweepPoint> points(count);
  if (!quiet)
    std::fprintf(stderr, "sweeping cord %d (vertex %d, l0 %.3f mm) over %s, %s\n", sweep.cord,
                 sweep.vertex(), sweep.base(), counted(count, "scale").c_str(),
                 counted(threads, "thread").c_str());
  // Each point is an independent full closure from the open state; results go to their own
  // slot, so the output does not depend on the thread count or the order of completion. The
  // progress lines come in scale order too: a finished point is printed once every point
  // before it is.
  InOrderProgress progress(count, [&](int i) {
    if (quiet) return true;
    return printProgressLine(points[i], i, count);
  });
  // The sweep fails at its lowest failing scale: a failed point throws, and parallelFor then
  // runs only the scales below it (one of them may fail too) and rethrows the lowest, as with
  // one thread: the same error for any thread count, without running the rest (a diverging
  // sweep ran every one of its closures before failing). The points say which failed.
  struct ScaleFailed {};
  const auto sweepPoint = [&](int i) {
    points[i] = sweep.closeAt(i);
    progress.finished(i);
    if (!points[i].error.empty()) throw ScaleFailed{};
  };
  try {
    parallelFor(count, std::max(1, threads), sweepPoint);
  } catch (const ScaleFailed&) {
    // Reported by reportFailedScale, from the lowest point with an error.
  }
  return points;
}

// The lowest failed point, reported on stderr. Returns kExitOk or the failure's exit code.
int reportFailedScale(const std::vector<SweepPoint>& points, const std::string& case_dir) {
  for (const SweepPoint& p : points) {
    if (!p.error.empty()) {
      std::cerr << "error: " << case_dir << ": "
                << (p.diverged ? "simulation failed" : "closure refused") << " at scale " << p.scale
                << ": " << p.error << "\n";
      return p.diverged ? kExitSimulationFailed : kExitBadInput;
    }
  }
  return kExitOk;
}

std::ptrdiff_t closuresWithSelfIntersections(const std::vector<SweepPoint>& points) {
  return std::count_if(points.begin(), points.end(),
                       [](const SweepPoint& p) { return p.self_intersections > 0; });
}

// Positions of leaflets passing through each other are no valve's, whatever the noise says.
void warnOfSelfIntersections(const std::vector<SweepPoint>& points) {
  const auto crossed = closuresWithSelfIntersections(points);
  if (crossed > 0)
    printWarning(
        "sweep-cord: in %ld of %d closures the leaflets pass through each other (sweep.csv, "
        "self_intersections): their positions are not a valve's\n",
        static_cast<long>(crossed), static_cast<int>(points.size()));
}

// The sweep's columns, one entry per scale.
struct SweepSeries {
  std::vector<double> s, deviation, height, x, y, z;
};

SweepSeries seriesOf(const std::vector<SweepPoint>& points) {
  SweepSeries series;
  for (const SweepPoint& p : points) {
    series.s.push_back(p.scale);
    series.deviation.push_back(p.mean_deviation);
    series.height.push_back(p.height);
    series.x.push_back(p.vertex.x()), series.y.push_back(p.vertex.y());
    series.z.push_back(p.vertex.z());
  }
  return series;
}

// sweep.json: the sweep's parameters and the noise figures of each measure.
nlohmann::json sweepSummary(const SweepCordOptions& options, const CordSweep& sweep,
                            const std::vector<SweepPoint>& points, const SweepSeries& series) {
  const std::vector<double>& s = series.s;
  const int window = options.window;
  const auto noiseOf = [&](const std::vector<double>& q) {
    return noiseJson(mapNoise(s, q, window), s, q);
  };
  nlohmann::json summary = {
      {"cord", sweep.cord},
      {"vertex", sweep.vertex()},
      {"base_rest_length_mm", sweep.base()},
      {"range", options.range},
      {"step", options.step},
      {"window", options.window},  // the noise figures' local quadratic: 2 window + 1 points
      {"all_converged",
       std::all_of(points.begin(), points.end(), [](const SweepPoint& p) { return p.converged; })},
      {"closures_with_self_intersections", closuresWithSelfIntersections(points)},
      {"vertex_height", noiseOf(series.height)},
      {"vertex_x", noiseOf(series.x)},
      {"vertex_y", noiseOf(series.y)},
      {"vertex_z", noiseOf(series.z)}};
  if (!options.settings_overrides.empty())
    summary["settings_overrides"] = options.settings_overrides;
  if (!options.tissue_file.empty()) summary["tissue_file"] = options.tissue_file;
  if (sweep.hasTracings()) summary["mean_deviation"] = noiseOf(series.deviation);
  return summary;
}

// sweep.svg's panels: the mean deviation to the tracings (when there are tracings) and the
// height of the cord's insertion, against the scale.
std::vector<PlotPanel> sweepPlots(const CordSweep& sweep, const SweepSeries& series) {
  // The sweep's scale multiplies the cord's length in the swept cord set (1 = as given), not
  // its seed rest length as the cord file's "scale" does: the axis says which.
  char axis[96];
  std::snprintf(axis, sizeof axis, "cord %d's length / %.3f mm (its length in the cord set)",
                sweep.cord, sweep.base());
  // The legends right of the frames: a map that rises to the right ran under them.
  constexpr double kLegendMargin = 170.0;
  std::vector<PlotPanel> panels;
  if (sweep.hasTracings()) {
    panels.push_back({"Mean deviation to the tracings",
                      axis,
                      "mean deviation (mm)",
                      {{"mean deviation", series.s, series.deviation, true, true}},
                      false,
                      kLegendMargin});
  }
  // The insertion: the cord's point between vertices when it has one, else its vertex (the
  // CSV's vertex_* columns keep their names for scripts written against them).
  panels.push_back({"Height of the cord's insertion above the closed annulus plane",
                    axis,
                    "height (mm)",
                    {{"insertion (nearest vertex " + std::to_string(sweep.vertex()) + ")", series.s,
                      series.height, true, true}},
                    false,
                    kLegendMargin});
  return panels;
}

// sweep.csv, sweep.svg and sweep.json into `out_dir`, all of them or none (StagedOutput).
StagedOutput::Published writeSweepOutputs(const std::string& out_dir,
                                          const std::vector<SweepPoint>& points,
                                          const std::vector<PlotPanel>& panels,
                                          const nlohmann::json& summary) {
  StagedOutput staged(out_dir, sweepCordOutputFiles(), {}, "sweep-cord");
  const std::filesystem::path& out = staged.dir();
  writeFileAtomically(out / "sweep.csv", sweepCsv(points));
  writeFileAtomically(out / "sweep.svg", svgLinePlots(panels, 1, 720, 360));
  writeFileAtomically(out / "sweep.json", summary.dump(2) + "\n");
  return staged.publish();
}

// One line per measure with a verdict (mean deviation, when there are tracings, and vertex
// height): its noise, the change a 0.5 % step makes and whether the map is smooth.
void printVerdicts(const nlohmann::json& summary) {
  for (const char* key : {"mean_deviation", "vertex_height"}) {
    if (!summary.contains(key)) continue;
    const auto& n = summary[key];
    // With no noise the ratio is infinite (null once the JSON is written).
    char ratio[32] = "- (no noise)";
    if (const double r = n["signal_to_noise"].get<double>(); std::isfinite(r))
      std::snprintf(ratio, sizeof ratio, "%.3g", r);
    std::printf(
        "%-15s noise rms %.2e max %.2e mm | change over a 0.5%% step %.2e mm | "
        "signal/noise %s | %s\n",
        key, n["noise_rms"].get<double>(), n["noise_max"].get<double>(),
        n["change_over_0.5_percent"].get<double>(), ratio, verdictText(n).c_str());
  }
}

}  // namespace

int runSweepCord(const SweepCordOptions& options) {
  const std::optional<ScaleGrid> grid = checkedScaleGrid(options);
  if (!grid) return kExitBadInput;
  auto loaded =
      loadCaseWithCords("sweep-cord", options.case_dir, options.tissue_file, options.cords_file);
  if (!loaded) return kExitBadInput;
  ValveCase& valve_case = loaded->valve_case;
  const CordSet& cords = loaded->cords;
  const int cord = sweptCord(options, valve_case, cords);
  if (cord < 0) return kExitBadInput;
  const auto settings =
      caseSettingsOrReport(valve_case, options.case_dir, SettingsUse::kClose, "sweep-cord",
                           options.settings_overrides, options.tissue_file);
  if (!settings) return kExitBadInput;

  const CordSweep sweep{valve_case, cords, *settings, cord, *grid};
  const std::vector<SweepPoint> points = runClosures(sweep, options.threads, options.quiet);
  if (const int failed = reportFailedScale(points, options.case_dir); failed != kExitOk)
    return failed;
  warnOfSelfIntersections(points);

  const SweepSeries series = seriesOf(points);
  const nlohmann::json summary = sweepSummary(options, sweep, points, series);
  const StagedOutput::Published published =
      writeSweepOutputs(options.out_dir, points, sweepPlots(sweep, series), summary);
  printVerdicts(summary);
  std::cout << wroteLine(options.out_dir, published) << "\n";
  return kExitOk;
}

std::vector<std::string> sweepCordOutputFiles() { return {"sweep.csv", "sweep.svg", "sweep.json"}; }

}  // namespace chordfit::cli
