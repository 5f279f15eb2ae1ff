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

double valveReachMm(const Eigen::MatrixXd& mesh_V) {
  return std::max(50.0, boundingDiagonal(mesh_V));
}

namespace {

// How far p lies from the box [lo, hi] (the per-axis excess beyond it); NaN for NaN.
double distanceFromBox(const Eigen::RowVector3d& lo, const Eigen::RowVector3d& hi,
                       const Eigen::RowVector3d& p) {
  return (lo - p).cwiseMax(p - hi).cwiseMax(0.0).norm();
}

void reportFarPoint(const Eigen::RowVector3d& p, double distance, double reach,
                    const std::string& file, const std::string& where, Diagnostics& diagnostics) {
  char position[96];
  std::snprintf(position, sizeof position, "(%.4g, %.4g, %.4g)", p(0), p(1), p(2));
  diagnostics.error(file, where,
                    std::string(position) + " lies " + millimetres(distance) +
                        " from the valve mesh (every point must be within " + millimetres(reach) +
                        " of its bounding box)");
}

}  // namespace

bool checkPointsNearValve(const Eigen::MatrixXd& mesh_V, const Eigen::MatrixXd& points,
                          const std::string& file, const std::string& where,
                          Diagnostics& diagnostics) {
  if (mesh_V.rows() == 0) return true;
  const Eigen::RowVector3d lo = mesh_V.colwise().minCoeff(), hi = mesh_V.colwise().maxCoeff();
  const double reach = valveReachMm(mesh_V);
  constexpr int kReported = 3;
  int far = 0;
  for (Eigen::Index k = 0; k < points.rows(); ++k) {
    const Eigen::RowVector3d p = points.row(k);
    const double distance = distanceFromBox(lo, hi, p);
    if (distance <= reach) continue;  // false for NaN too: reported as far
    if (++far <= kReported)
      reportFarPoint(p, distance, reach, file, where + "[" + std::to_string(k) + "]", diagnostics);
  }
  if (far > kReported) {
    diagnostics.error(file, where,
                      std::to_string(far - kReported) + " more point(s) as far from the valve");
  }
  return far == 0;
}

bool checkTipsNearValve(const Eigen::MatrixXd& mesh_V, const std::vector<PmTip>& tips,
                        const std::string& file, Diagnostics& diagnostics) {
  if (mesh_V.rows() == 0) return true;
  const Eigen::RowVector3d lo = mesh_V.colwise().minCoeff(), hi = mesh_V.colwise().maxCoeff();
  const double reach = valveReachMm(mesh_V);
  bool ok = true;
  auto check = [&](const Eigen::Vector3d& position, const std::string& where) {
    const double distance = distanceFromBox(lo, hi, position.transpose());
    if (distance <= reach) return;
    reportFarPoint(position.transpose(), distance, reach, file, where, diagnostics);
    ok = false;
  };
  for (std::size_t t = 0; t < tips.size(); ++t) {
    const std::string where = "tips[" + std::to_string(t) + "]";
    check(tips[t].position, where + ".position");
    if (tips[t].closed_position) check(*tips[t].closed_position, where + ".closed_position");
  }
  return ok;
}

}  // namespace chordfit
