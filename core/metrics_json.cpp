#include "core/metrics_json.h"

#include <cmath>

namespace chordfit {

namespace {
nlohmann::json numberOrNull(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}
}  // namespace

nlohmann::json metricsJson(const ValveMetrics& m) {
  nlohmann::json j;
  j["tracing_points"] = m.deviation.count;
  j["min_mm"] = numberOrNull(m.deviation.min);
  j["median_mm"] = numberOrNull(m.deviation.median);
  j["max_mm"] = numberOrNull(m.deviation.max);
  j["mean_mm"] = numberOrNull(m.deviation.mean);
  j["sd_mm"] = numberOrNull(m.deviation.sd);
  j["area_mm2"] = m.area_mm2;
  j["prolapse_segments"] = m.mesh_prolapse.segments;
  j["prolapse_max_height_mm"] = numberOrNull(m.mesh_prolapse.max_height_mm);
  j["orifice_coverage"] = numberOrNull(m.orifice.coverage());
  j["open_orifice_area_mm2"] = m.orifice.open_area_mm2;
  j["orifice_area_mm2"] = m.orifice.orifice_area_mm2;
  j["orifice_tissue_radius_mm"] = m.orifice.tissue_radius_mm;
  j["self_intersections"] = m.self_intersections;
  if (m.has_tracings) {
    j["tracing_prolapse_segments"] = m.tracing_prolapse.segments;
    j["section_prolapse_segments"] = m.section_prolapse.segments;
    j["prolapse_reconstructed"] = m.prolapse_reconstructed;
    j["tissue_prolapse_reconstructed"] = m.tissue_prolapse_reconstructed;
  } else {
    j["tracing_prolapse_segments"] = nullptr;
    j["section_prolapse_segments"] = nullptr;
    j["prolapse_reconstructed"] = nullptr;
    j["tissue_prolapse_reconstructed"] = nullptr;
  }
  return j;
}

}  // namespace chordfit
