// Curves in delimited text, for tracings and annuli exported by other tools:
//   - 3D Slicer's legacy fiducial list (*.fcsv): '#' header lines, among them
//     "# CoordinateSystem = LPS | RAS | 0 (RAS) | 1 (LPS)" (RAS when absent: Slicer wrote RAS
//     before the line existed) and "# columns = id,x,y,z,..." naming the columns; one point
//     per data line, comma separated.
//   - plain point lists (*.csv, *.txt): one point per line, fields separated by commas,
//     semicolons, tabs or spaces; lines starting with '#' and blank lines skipped. An optional
//     header row names the coordinate columns and with them the coordinate system: x,y,z or
//     l,p,s (LPS, the case convention) or r,a,s (RAS, converted); without a header the first
//     three fields are x, y, z in LPS.
// Points are returned in LPS, as curve_io.h's readers do. Problems name the file and line.
#pragma once

#include <filesystem>
#include <string>

#include "core/curve_io.h"
#include "core/diagnostics.h"

namespace chordfit {

// True for the extensions read here (.fcsv, .csv, .txt; any letter case).
bool isDelimitedCurveFile(const std::filesystem::path& path);

// Reads one open curve from `path` (`file`: the name used in problems). Never throws; returns
// false with problems added to `diagnostics`.
bool readDelimitedCurve(const std::filesystem::path& path, const std::string& file, Curve& curve,
                        Diagnostics& diagnostics);

}  // namespace chordfit
