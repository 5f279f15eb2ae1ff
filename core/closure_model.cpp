#include "core/closure_model.h"

#include <algorithm>
#include <vector>

#include <Eigen/Geometry>

#include "core/annulus_plane.h"
#include "core/cord_insertion.h"
#include "core/mesh_topology.h"

namespace chordfit {
namespace {

using Vec3 = Eigen::Vector3d;

}  // namespace

bool closureModel(const ValveCase& valve_case, const CordSet& cords, ClosurePhase phase,
                  SimulationModel& model, std::string& error) {
  const ValveMesh& mesh = valve_case.mesh;
  const int n = static_cast<int>(mesh.V.rows());
  error.clear();
  if (n == 0 || mesh.F.rows() == 0) {
    error = "mesh: empty";
    return false;
  }
  if (mesh.F.minCoeff() < 0 || mesh.F.maxCoeff() >= n) {
    error = "mesh: face index out of range";
    return false;
  }
  if (mesh.annulus.size() < 3 || mesh.annulus.minCoeff() < 0 || mesh.annulus.maxCoeff() >= n) {
    error = "mesh: annulus ring needs >= 3 vertex indices in range";
    return false;
  }
  const Eigen::Index ring = mesh.annulus.size();
  if (valve_case.annulus_closed.rows() != 0 &&
      (valve_case.annulus_closed.rows() != ring || valve_case.annulus_closed.cols() != 3)) {
    error = "annulus_closed: expected one closed position per annulus vertex (" +
            std::to_string(ring) + " by 3)";
    return false;
  }
  for (size_t c = 0; c < cords.cords.size(); ++c) {
    const Cord& cord = cords.cords[c];
    if (cord.tip < 0 || cord.tip >= static_cast<int>(cords.tips.size()) || cord.vertex < 0 ||
        cord.vertex >= n) {
      error = "cords[" + std::to_string(c) + "]: tip or vertex index out of range";
      return false;
    }
    const std::string point_problem = cord.point ? cordPointProblem(*cord.point, n) : "";
    if (!point_problem.empty()) {
      error = "cords[" + std::to_string(c) + "].point: " + point_problem;
      return false;
    }
    if (const std::string problem = cordOnRingProblem(cord, mesh.annulus); !problem.empty()) {
      error = "cords[" + std::to_string(c) + "]: " + problem;
      return false;
    }
    if (!(cord.rest_length > 0.0)) {
      error = "cords[" + std::to_string(c) + "]: rest length must be > 0";
      return false;
    }
  }

  const AnnulusFrame frame = openAnnulusFrame(mesh);
  const Vec3 n_ap = frame.plane.normal;

  // Consistent winding, then per component make the winding normal point to the atrial side:
  // toward n_AP and toward the valve axis (the line through the annulus centre along n_AP).
  // Both hold for the atrial face of a leaflet hanging from the annulus like a funnel; the
  // axis term decides for near-vertical leaflets, the n_AP term for flat ones.
  Eigen::MatrixXi F;
  orientFacesConsistently(mesh.F, F);
  const Eigen::VectorXi component = faceComponents(F);
  const int num_components = component.size() ? component.maxCoeff() + 1 : 0;
  std::vector<double> score(num_components, 0.0);
  for (int f = 0; f < F.rows(); ++f) {
    const Vec3 a = mesh.V.row(F(f, 0)).transpose(), b = mesh.V.row(F(f, 1)).transpose(),
               c = mesh.V.row(F(f, 2)).transpose();
    const Vec3 N = (b - a).cross(c - a);  // 2 A n
    const Vec3 centroid = (a + b + c) / 3.0;
    Vec3 inward = frame.plane.centre - centroid;
    inward -= inward.dot(n_ap) * n_ap;
    const double len = inward.norm();
    if (len > 1e-12) inward /= len;
    score[component(f)] += N.dot(n_ap + inward);
  }
  for (int f = 0; f < F.rows(); ++f)
    if (score[component(f)] < 0.0) std::swap(F(f, 1), F(f, 2));

  model = SimulationModel();
  model.V_rest = mesh.V;
  model.F = F;
  model.fixed = mesh.annulus;
  Eigen::MatrixXd open_ring(ring, 3);
  for (Eigen::Index k = 0; k < ring; ++k) open_ring.row(k) = mesh.V.row(mesh.annulus(k));
  const Eigen::MatrixXd closed_ring =
      valve_case.annulus_closed.rows() == ring ? valve_case.annulus_closed : open_ring;
  const int num_tips = static_cast<int>(cords.tips.size());
  Eigen::MatrixXd tips_open(num_tips, 3), tips_closed(num_tips, 3);
  for (int k = 0; k < num_tips; ++k) {
    tips_open.row(k) = cords.tips[k].position.transpose();
    tips_closed.row(k) = cords.tips[k].closed_position.value_or(cords.tips[k].position).transpose();
  }
  const bool closing = phase == ClosurePhase::kClose;
  model.fixed_start = closing ? open_ring : closed_ring;
  model.fixed_end = closing ? closed_ring : open_ring;
  model.tip_start = closing ? tips_open : tips_closed;
  model.tip_end = closing ? tips_closed : tips_open;
  for (const Cord& cord : cords.cords)
    model.cords.push_back({cord.tip, cord.vertex, cord.rest_length, cord.compliance, cord.point});
  model.tissue_stiffness = valve_case.tissue_stiffness;
  model.flow_direction = n_ap;  // simulate() reverses it (and the pressure) for kOpen
  return true;
}

SimulationResult simulateClosure(const ValveCase& valve_case, const CordSet& cords,
                                 const SimulationSettings& settings,
                                 const Eigen::MatrixXd* warm_start) {
  SimulationResult result;
  SimulationModel model;
  if (!closureModel(valve_case, cords, settings.phase, model, result.error)) return result;
  if (settings.phase == ClosurePhase::kOpen && !warm_start) {
    result.error = "opening needs a start state (the closed valve)";
    return result;
  }
  return simulate(model, settings, warm_start);
}

}  // namespace chordfit
