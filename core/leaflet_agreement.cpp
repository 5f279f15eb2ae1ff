#include "core/leaflet_agreement.h"

#include <cmath>

namespace chordfit {

double tracingLeafletAgreement(const ValveMesh& mesh, const std::vector<Tracing>& tracings) {
  int agree = 0, labelled = 0;
  for (const Tracing& t : tracings) {
    if (t.leaflet < 0) continue;
    for (Eigen::Index i = 0; i < t.points.rows(); ++i) {
      Eigen::Index nearest = 0;
      (mesh.V.rowwise() - t.points.row(i)).rowwise().squaredNorm().minCoeff(&nearest);
      agree += mesh.leaflet(nearest) == t.leaflet ? 1 : 0;
      ++labelled;
    }
  }
  return labelled > 0 ? static_cast<double>(agree) / labelled : NAN;
}

}  // namespace chordfit
