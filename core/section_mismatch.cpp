#include "core/section_mismatch.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/metrics.h"
#include "core/tracing_sampler.h"

namespace chordfit {

namespace {

// Distance from p to the segment [a, b].
double segmentDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                       const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double length2 = ab.squaredNorm();
  const double t = length2 > 0.0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

// 3-point Gauss-Legendre on [0, 1] (Abramowitz and Stegun 25.4.29, mapped from [-1, 1]).
constexpr double kGaussOffset = 0.3872983346207417;  // sqrt(3/5) / 2
const double kGaussNodes[3] = {0.5 - kGaussOffset, 0.5, 0.5 + kGaussOffset};
const double kGaussWeights[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};

}  // namespace

SectionMismatch::SectionMismatch(const ValveCase& valve_case, const SectionMismatchOptions& options)
    : F_(valve_case.mesh.F),
      face_leaflet_(faceLeaflets(valve_case.mesh.F, valve_case.mesh.leaflet)),
      leaflets_(valve_case.mesh.leaflet.size() > 0 ? valve_case.mesh.leaflet.maxCoeff() + 1 : 0),
      options_(options) {
  if (valve_case.tracings.empty()) return;
  const ClosedAnnulus closed = closedAnnulus(valve_case);
  for (const ImagePlane& image_plane : tracingPlanes(valve_case.tracings, closed.frame)) {
    Plane plane{image_plane.origin, image_plane.normal, {}};
    std::vector<std::vector<Eigen::Matrix<double, 1, 6>>> rows(leaflets_);
    for (const Tracing& t : valve_case.tracings) {
      if (!tracedOnPlane(t, image_plane)) continue;
      for (int leaflet = 0; leaflet < leaflets_; ++leaflet) {
        if (t.leaflet >= 0 && t.leaflet != leaflet) continue;
        for (Eigen::Index i = 0; i + 1 < t.points.rows(); ++i) {
          Eigen::Matrix<double, 1, 6> row;
          row << t.points.row(i), t.points.row(i + 1);
          rows[leaflet].push_back(row);
        }
      }
    }
    for (int leaflet = 0; leaflet < leaflets_; ++leaflet) {
      Eigen::MatrixXd segments(rows[leaflet].size(), 6);
      for (std::size_t r = 0; r < rows[leaflet].size(); ++r) segments.row(r) = rows[leaflet][r];
      plane.segments.push_back(std::move(segments));
    }
    planes_.push_back(std::move(plane));
  }
}

Eigen::VectorXd SectionMismatch::excess(const Eigen::MatrixXd& V) const {
  Eigen::VectorXd E = Eigen::VectorXd::Zero(termCount());
  for (std::size_t k = 0; k < planes_.size(); ++k) {
    const Plane& plane = planes_[k];
    for (const SectionPolyline& section :
         planeSection(V, F_, face_leaflet_, plane.origin, plane.normal)) {
      if (section.leaflet < 0 || section.leaflet >= leaflets_) continue;
      const Eigen::MatrixXd& segments = plane.segments[section.leaflet];
      if (segments.rows() == 0) continue;  // nothing of this leaflet traced on the plane
      double integral = 0.0;
      for (Eigen::Index i = 0; i + 1 < section.points.rows(); ++i) {
        const Eigen::Vector3d a = section.points.row(i).transpose();
        const Eigen::Vector3d b = section.points.row(i + 1).transpose();
        const double length = (b - a).norm();
        if (length == 0.0) continue;
        for (int g = 0; g < 3; ++g) {
          const Eigen::Vector3d s = a + kGaussNodes[g] * (b - a);
          double d = std::numeric_limits<double>::infinity();
          for (Eigen::Index j = 0; j < segments.rows(); ++j) {
            d = std::min(d, segmentDistance(s, segments.row(j).head<3>().transpose(),
                                            segments.row(j).tail<3>().transpose()));
          }
          const double stray = std::clamp(d - options_.tolerance_mm, 0.0, options_.cap_mm);
          integral += kGaussWeights[g] * length * stray * stray;
        }
      }
      E(static_cast<Eigen::Index>(k) * leaflets_ + section.leaflet) +=
          integral / options_.unit_length_mm;
    }
  }
  return E;
}

}  // namespace chordfit
