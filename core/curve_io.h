// Curve readers: 3D Slicer markups JSON (*.mrk.json: Curve / ClosedCurve / Fiducial lists,
// coordinateSystem LPS or RAS) and plain JSON point lists ({"points": [[x,y,z], ...]} or a
// bare [[x,y,z], ...] array), and by extension delimited text (*.fcsv, *.csv, *.txt;
// curve_csv.h). All points are returned in the case coordinate system, LPS (3D Slicer's file
// convention): RAS input is converted by negating x and y.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/diagnostics.h"

namespace chordfit {

struct Curve {
  Eigen::MatrixXd points;  // #P by 3, mm, LPS
  bool closed = false;     // Slicer ClosedCurve (plain lists: "closed": true)
  // How the file's coordinate system was read, for a message about points that look turned
  // half a turn about S (RAS read as LPS, or the reverse): whether they were converted from
  // RAS, and what to write in this file's format to have them read in the other system.
  bool read_as_ras = false;
  std::string other_frame_syntax;
  // Where each point stands in its file, as a message names it: "line 4" in a delimited text
  // file, "points[2]" in a point list, "markups[0].controlPoints[3]" in a markups file (one per
  // row of `points`), so that a later check of a point (far from the valve) can point into the
  // file rather than at the field that named it.
  std::vector<std::string> point_wheres;
};

// Reads one curve. For a markups file with several markups, `markup_index` picks one.
// Never throws on bad content; returns false with problems added to `diagnostics`.
bool readCurve(const std::filesystem::path& path, Curve& curve, Diagnostics& diagnostics,
               const std::string& display_name = "", int markup_index = 0);

// For points that fit once x and y are negated (turned half a turn about S: RAS read as LPS,
// or the reverse): the question to ask, in the words of the file they came from, e.g. "the file
// was read as RAS; are they in LPS? (say \"# CoordinateSystem = LPS\" in the file's header)";
// `source` nullptr: points inline in a JSON file, read as LPS.
std::string otherFrameQuestion(const Curve* source);

// Writes a plain JSON point list atomically.
void writePointList(const std::filesystem::path& path, const Eigen::MatrixXd& points,
                    bool closed = false);

}  // namespace chordfit
