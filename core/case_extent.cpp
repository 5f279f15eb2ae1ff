#include "core/case_extent.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace chordfit {
namespace {

std::string millimetres(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g mm", value);
  return text;
}

}  // namespace

double boundingDiagonal(const Eigen::MatrixXd& V) {
  if (V.rows() == 0) return 0.0;
  return (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
}

bool checkValveSpan(const Eigen::MatrixXd& V, const std::string& file, Diagnostics& diagnostics) {
  const double span = boundingDiagonal(V);
  if (span >= kMinValveSpanMm && span <= kMaxValveSpanMm) return true;
  diagnostics.error(file, "vertices",
                    "the mesh spans " + millimetres(span) + " (bounding-box diagonal); a mitral " +
                        "valve spans 30-60 mm and coordinates must be in millimetres (accepted: " +
                        millimetres(kMinValveSpanMm) + " to " + millimetres(kMaxValveSpanMm) + ")");
  return false;
}

Eigen::MatrixXd tipPositions(const std::vector<PmTip>& tips) {
  std::vector<Eigen::Vector3d> rows;
  for (const PmTip& tip : tips) {
    rows.push_back(tip.position);
    if (tip.closed_position) rows.push_back(*tip.closed_position);
  }
  Eigen::MatrixXd out(static_cast<Eigen::Index>(rows.size()), 3);
  for (std::size_t k = 0; k < rows.size(); ++k) out.row(static_cast<Eigen::Index>(k)) = rows[k];
  return out;
}

double valveReachMm(const Eigen::MatrixXd& mesh_V) {
  return std::max(50.0, boundingDiagonal(mesh_V));
}

bool checkPointsNearValve(const Eigen::MatrixXd& mesh_V, const Eigen::MatrixXd& points,
                          const std::string& file, const std::string& where,
                          Diagnostics& diagnostics) {
  if (mesh_V.rows() == 0) return true;
  const Eigen::RowVector3d lo = mesh_V.colwise().minCoeff(), hi = mesh_V.colwise().maxCoeff();
  const double reach = valveReachMm(mesh_V);
  constexpr int kReported = 3;
  int far = 0;
  for (Eigen::Index k = 0; k < points.rows(); ++k) {
    // Distance from the box: the per-axis excess beyond it.
    const Eigen::RowVector3d p = points.row(k);
    const Eigen::RowVector3d excess = (lo - p).cwiseMax(p - hi).cwiseMax(0.0);
    const double distance = excess.norm();
    if (distance <= reach) continue;  // also false for NaN: reported below as far
    if (++far <= kReported) {
      char position[96];
      std::snprintf(position, sizeof position, "(%.4g, %.4g, %.4g)", p(0), p(1), p(2));
      diagnostics.error(file, where + "[" + std::to_string(k) + "]",
                        std::string(position) + " lies " + millimetres(distance) +
                            " from the valve mesh (every point must be within " +
                            millimetres(reach) + " of its bounding box)");
    }
  }
  if (far > kReported) {
    diagnostics.error(file, where,
                      std::to_string(far - kReported) + " more point(s) as far from the valve");
  }
  return far == 0;
}

}  // namespace chordfit
