// JSON form of ValveMetrics (the keys documented in docs/case-format.md, "metrics.json").
#pragma once

#include <nlohmann/json.hpp>

#include "core/metrics.h"

namespace chordfit {

// Keys: min_mm, median_mm, max_mm, mean_mm, sd_mm, tracing_points (deviation; null without
// tracings), area_mm2, prolapse_segments, prolapse_max_height_mm (simulated mesh),
// orifice_coverage, open_orifice_area_mm2, orifice_area_mm2 (orifice_coverage.h),
// tracing_prolapse_segments, section_prolapse_segments, prolapse_reconstructed (sections vs
// tracings, Table 1), tissue_prolapse_reconstructed (null without tracings),
// orifice_tissue_radius_mm, self_intersections.
nlohmann::json metricsJson(const ValveMetrics& metrics);

}  // namespace chordfit
