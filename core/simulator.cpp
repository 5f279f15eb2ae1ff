#include "core/simulator.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <initializer_list>
#include <limits>
#include <memory>

#include "core/contact.h"
#include "core/cord_insertion.h"
#include "core/mesh_topology.h"
#include "core/metrics.h"
#include "core/sweep_team.h"
#include "core/xpbd_constraints.h"

namespace chordfit {
namespace {

using Vec3 = Eigen::Vector3d;
using Map3 = Eigen::Map<Eigen::Vector3d>;
using CMap3 = Eigen::Map<const Eigen::Vector3d>;

// CPU time of the calling thread (less sensitive than wall time to other load on the machine).
double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// Smooth ramp 0 -> 1 (smoothstep), so boundary velocities start and end at zero.
double ramp(double t, double duration) {
  if (duration <= 0.0) return 1.0;
  const double s = std::clamp(t / duration, 0.0, 1.0);
  return s * s * (3.0 - 2.0 * s);
}

std::string validate(const SimulationModel& m, const SimulationSettings& s) {
  const int n = static_cast<int>(m.V_rest.rows());
  if (n == 0 || m.V_rest.cols() != 3) return "model: V_rest must be #V by 3 and non-empty";
  if (m.F.cols() != 3 || m.F.rows() == 0) return "model: F must be #F by 3 and non-empty";
  if (m.F.minCoeff() < 0 || m.F.maxCoeff() >= n) return "model: face index out of range";
  if (!m.V_rest.allFinite()) return "model: non-finite rest position";
  if (m.fixed.size() > 0 && (m.fixed.minCoeff() < 0 || m.fixed.maxCoeff() >= n))
    return "model: fixed vertex index out of range";
  if (m.fixed_start.rows() != m.fixed.size() || m.fixed_end.rows() != m.fixed.size())
    return "model: fixed_start / fixed_end must have one row per fixed vertex";
  if (m.tip_start.rows() != m.tip_end.rows()) return "model: tip_start / tip_end sizes differ";
  if (!m.fixed_start.allFinite() || !m.fixed_end.allFinite() || !m.tip_start.allFinite() ||
      !m.tip_end.allFinite())
    return "model: non-finite boundary or tip position";
  for (const auto& c : m.cords) {
    if (c.tip < 0 || c.tip >= m.tip_start.rows()) return "model: cord tip index out of range";
    if (c.vertex < 0 || c.vertex >= n) return "model: cord vertex index out of range";
    const std::string point_problem = c.point ? cordPointProblem(*c.point, n) : "";
    if (!point_problem.empty()) return "model: cord point: " + point_problem;
    if (!(c.rest_length > 0.0) || !std::isfinite(c.rest_length))
      return "model: cord rest length must be positive";
    if (!(c.compliance >= 0.0)) return "model: cord compliance must be >= 0";
  }
  if (m.tissue_stiffness.size() != 0 && m.tissue_stiffness.size() != n)
    return "model: tissue_stiffness must have one factor per vertex";
  if (!(m.tissue_stiffness.array() > 0.0).all() || !m.tissue_stiffness.allFinite())
    return "model: tissue_stiffness factors must be positive and finite";
  const auto problems = settingsProblems(s);
  if (!problems.empty()) return "settings: " + problems[0].key + ": " + problems[0].what;
  return "";
}

// The upper median (the element at index size / 2 once sorted); 0 for none.
double upperMedian(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// Constraint arrays and per-vertex data, precomputed from the rest state.
struct System {
  int n = 0;
  std::vector<double> w;  // inverse masses, 0 for Dirichlet vertices
  std::vector<DistanceConstraint> edges;
  std::vector<AreaConstraint> areas;
  std::vector<AreaConstraint> area_floors;  // rest_area = the floor (xpbd_constraints.h)
  std::vector<BendingConstraint> bends;
  std::vector<CordConstraint> cords;
  // Colour classes of the four arrays above (orderByColour), for the parallel sweeps.
  ColourClasses edge_classes, area_classes, floor_classes, bend_classes;
  // Per-vertex stiffness k_i = sum over the material constraints of |grad_i C|^2 / alpha at
  // rest (N/mm), and its median ratio to the mass over free vertices (1/ms^2).
  std::vector<double> stiffness;
  double median_stiffness_over_mass = 0.0;
  // Median regional tissue factor over the free vertices (1 when uniform): the valve's
  // typical tissue is E times it (timeStepMs).
  double median_tissue_factor = 1.0;
  // Median over the free vertices of the bending hinges' share of k_i (timeStepMs).
  double median_bending_share = 0.0;
};

System buildSystem(const SimulationModel& m, const SimulationSettings& s) {
  System sys;
  const int n = sys.n = static_cast<int>(m.V_rest.rows());
  const LeafletMaterial& mat = s.material;
  auto pos = [&](int i) { return Vec3(m.V_rest.row(i).transpose()); };

  Eigen::VectorXd face_area(m.F.rows());
  std::vector<double> vertex_area(n, 0.0);
  for (int f = 0; f < m.F.rows(); ++f) {
    face_area(f) = triangleArea(pos(m.F(f, 0)), pos(m.F(f, 1)), pos(m.F(f, 2)));
    for (int c = 0; c < 3; ++c) vertex_area[m.F(f, c)] += face_area(f) / 3.0;
  }
  std::vector<double> mass(n);
  sys.w.assign(n, 0.0);
  for (int i = 0; i < n; ++i) {
    mass[i] = lumpedMass(mat, vertex_area[i]);
    sys.w[i] = mass[i] > 0.0 ? 1.0 / mass[i] : 0.0;  // isolated vertices do not move
  }
  for (int k = 0; k < m.fixed.size(); ++k) sys.w[m.fixed(k)] = 0.0;

  // Regional tissue factor of a constraint: the mean over its vertices (1 when uniform).
  const bool regional = m.tissue_stiffness.size() == n;
  auto tissue = [&](std::initializer_list<int> ids) {
    if (!regional) return 1.0;
    double sum = 0.0;
    for (int i : ids) sum += m.tissue_stiffness(i);
    return sum / static_cast<double>(ids.size());
  };
  Eigen::MatrixXi E, EF, EI;
  edgeFlaps(m.F, E, EF, EI);
  std::vector<double> vertex_stiffness(n, 0.0);
  std::vector<double> bending_stiffness(n, 0.0);
  sys.edges.reserve(E.rows());
  for (int e = 0; e < E.rows(); ++e) {
    DistanceConstraint c;
    c.i = E(e, 0), c.j = E(e, 1);
    c.rest = (pos(c.i) - pos(c.j)).norm();
    double adjacent = face_area(EF(e, 0));
    if (EF(e, 1) >= 0) adjacent += face_area(EF(e, 1));
    if (c.rest <= 0.0 || adjacent <= 0.0) continue;  // degenerate: no stiffness to give
    c.compliance = edgeCompliance(mat, adjacent, c.rest) / tissue({c.i, c.j});
    vertex_stiffness[c.i] += 1.0 / c.compliance;
    vertex_stiffness[c.j] += 1.0 / c.compliance;
    sys.edges.push_back(c);
  }
  if (mat.area_bulk_fraction > 0.0) {
    for (int f = 0; f < m.F.rows(); ++f) {
      if (face_area(f) <= 0.0) continue;
      AreaConstraint c;
      c.a = m.F(f, 0), c.b = m.F(f, 1), c.c = m.F(f, 2);
      c.rest_area = face_area(f);
      c.compliance = areaCompliance(mat, face_area(f)) / tissue({c.a, c.b, c.c});
      Vec3 g[3];
      triangleArea(pos(c.a), pos(c.b), pos(c.c), g);
      vertex_stiffness[c.a] += g[0].squaredNorm() / c.compliance;
      vertex_stiffness[c.b] += g[1].squaredNorm() / c.compliance;
      vertex_stiffness[c.c] += g[2].squaredNorm() / c.compliance;
      sys.areas.push_back(c);
    }
  }
  if (s.area_floor_fraction > 0.0) {
    for (int f = 0; f < m.F.rows(); ++f) {
      if (face_area(f) <= 0.0) continue;
      AreaConstraint c;
      c.a = m.F(f, 0), c.b = m.F(f, 1), c.c = m.F(f, 2);
      c.rest_area = s.area_floor_fraction * face_area(f);
      sys.area_floors.push_back(c);
    }
  }
  const Eigen::MatrixXi Q = bendingQuads(m.F);
  for (int b = 0; b < Q.rows(); ++b) {
    BendingConstraint c;
    c.i = Q(b, 0), c.j = Q(b, 1), c.k = Q(b, 2), c.l = Q(b, 3);
    const double len = (pos(c.i) - pos(c.j)).norm();
    const double a1 = triangleArea(pos(c.i), pos(c.j), pos(c.k));
    const double a2 = triangleArea(pos(c.j), pos(c.i), pos(c.l));
    if (len <= 0.0 || a1 <= 0.0 || a2 <= 0.0) continue;
    Vec3 g[4];
    c.rest_angle = dihedralAngle(pos(c.i), pos(c.j), pos(c.k), pos(c.l), g);
    c.compliance = bendingCompliance(mat, a1 + a2, len) / tissue({c.i, c.j, c.k, c.l});
    const int ids[4] = {c.i, c.j, c.k, c.l};
    for (int q = 0; q < 4; ++q) {
      const double k = g[q].squaredNorm() / c.compliance;
      vertex_stiffness[ids[q]] += k;
      bending_stiffness[ids[q]] += k;
    }
    sys.bends.push_back(c);
  }
  for (const auto& cord : m.cords) {
    CordConstraint c;
    c.tip = cord.tip, c.rest = cord.rest_length, c.compliance = cord.compliance;
    CordInsertionWeights insertion =
        cordInsertionWeights(m.V_rest, m.F, cord.vertex, cord.point, s.cord_insertion_radius_mm);
    c.vertices = std::move(insertion.vertices);
    c.weights = std::move(insertion.weights);
    sys.cords.push_back(std::move(c));
  }
  // Independent consecutive constraints (see orderByColour); cords and contacts touch one
  // or few leaflet vertices each and stay in input order.
  sys.edge_classes = orderByColour(sys.edges, [](const DistanceConstraint& c) {
    return std::array<int, 2>{c.i, c.j};
  });
  const auto triangle = [](const AreaConstraint& c) { return std::array<int, 3>{c.a, c.b, c.c}; };
  sys.area_classes = orderByColour(sys.areas, triangle);
  sys.floor_classes = orderByColour(sys.area_floors, triangle);
  sys.bend_classes = orderByColour(sys.bends, [](const BendingConstraint& c) {
    return std::array<int, 4>{c.i, c.j, c.k, c.l};
  });
  std::vector<double> ratio, bending_share;
  for (int i = 0; i < n; ++i)
    if (sys.w[i] > 0.0 && vertex_stiffness[i] > 0.0) {
      ratio.push_back(vertex_stiffness[i] * sys.w[i]);
      bending_share.push_back(bending_stiffness[i] / vertex_stiffness[i]);
    }
  sys.median_stiffness_over_mass = upperMedian(std::move(ratio));
  sys.median_bending_share = upperMedian(std::move(bending_share));
  if (regional) {
    std::vector<double> factors;
    for (int i = 0; i < n; ++i)
      if (sys.w[i] > 0.0) factors.push_back(m.tissue_stiffness(i));
    if (!factors.empty()) sys.median_tissue_factor = upperMedian(std::move(factors));
  }
  sys.stiffness = std::move(vertex_stiffness);
  return sys;
}

// Accumulates the pressure force f_i = p sum_{T containing i} N_T / 6 (N_T = winding normal
// scaled by 2 A_T, so N_T / 6 = A_T n_T / 3: the area-weighted vertex normal).
void pressureForces(const Eigen::MatrixXi& F, const double* x, double p, double* f, int n) {
  std::fill(f, f + 3 * static_cast<long>(n), 0.0);
  const double scale = p / 6.0;
  for (int t = 0; t < F.rows(); ++t) {
    const int a = F(t, 0), b = F(t, 1), c = F(t, 2);
    const CMap3 xa(x + 3 * a), xb(x + 3 * b), xc(x + 3 * c);
    const Vec3 N = scale * (xb - xa).cross(xc - xa);
    Map3(f + 3 * a) += N;
    Map3(f + 3 * b) += N;
    Map3(f + 3 * c) += N;
  }
}

// usesEdgeContact on the mesh's unique edges (uniqueEdges(F)), which the Stepper needs anyway.
bool usesEdgeContactOnEdges(const SimulationSettings& settings, const Eigen::MatrixXd& V_rest,
                            const Eigen::MatrixXi& edges, double contact_thickness_mm) {
  if (settings.edge_contact) return true;
  if (!(settings.edge_contact_edge_ratio > 0.0) || edges.rows() == 0) return false;
  std::vector<double> lengths(static_cast<size_t>(edges.rows()));
  for (Eigen::Index e = 0; e < edges.rows(); ++e)
    lengths[static_cast<size_t>(e)] = (V_rest.row(edges(e, 0)) - V_rest.row(edges(e, 1))).norm();
  return upperMedian(std::move(lengths)) >= settings.edge_contact_edge_ratio * contact_thickness_mm;
}

// The divergence a sheet stretched to `area` (of `rest_area`) is, for SimulationResult::error.
std::string stretchedSheetError(double area, double rest_area, const std::string& when,
                                const SimulationSettings& settings) {
  char text[360];
  std::snprintf(text, sizeof text,
                "simulation diverged: the leaflets stretched to %.1f times their rest area (%.0f "
                "of %.0f mm²) %s; the tissue is far too soft for the load (youngs_modulus_mpa %g, "
                "pressure_mmhg %g, and any tissue factors) or the input pulls the sheet apart",
                area / rest_area, area, rest_area, when.c_str(),
                settings.material.youngs_modulus_mpa, settings.pressure_mmhg);
  return text;
}

// The state of one run and the three phases of a time step (Ten Minute Physics style: the
// loop in simulate() reads as predict / solve / update). Flat arrays x, x_prev, v: 3 #V.
class Stepper {
 public:
  Stepper(const SimulationModel& model, const SimulationSettings& settings, System sys, double dt,
          double max_step, double thickness, const Eigen::MatrixXd& start)
      : model_(model),
        settings_(settings),
        sys_(std::move(sys)),
        n_(sys_.n),
        dt_(dt),
        inv_dt2_(1.0 / (dt * dt)),
        max_step_(max_step),
        // A spread insertion pulled by the whole excess of a far over-stretched cord (the
        // cohort's, in the open state) moves as a block in one sweep and tears the mesh apart
        // (the fine normal-1 truth diverged at step 36); a point insertion is left as it was.
        max_cord_pull_(settings.cord_insertion_radius_mm > 0.0 ? max_step : 0.0),
        drag_decay_(dragDecay(dt, settings.drag_time_ms)),
        warm_(settings.warm_start_lambda),
        x_(3 * n_),
        x_prev_(3 * n_),
        v_(3 * n_, 0.0),
        force_(3 * n_),
        impulse_(warm_ ? 3 * n_ : 0, 0.0),
        contact_impulse_(warm_ ? 3 * n_ : 0, 0.0),
        tips_(3 * model.tip_start.rows()),
        lambda_edges_(sys_.edges.size()),
        lambda_areas_(sys_.areas.size()),
        lambda_bends_(sys_.bends.size()),
        lambda_cords_(sys_.cords.size()),
        lambda_floors_(sys_.area_floors.size(), 0.0),
        team_(settings.threads > 1 ? std::make_unique<SweepTeam>(settings.threads) : nullptr) {
    for (int i = 0; i < n_; ++i)
      for (int d = 0; d < 3; ++d) x_[3 * i + d] = start(i, d);
    if (settings.contact) {
      ContactOptions options;
      options.thickness_mm = thickness;
      options.margin_mm =
          settings.contact_margin_mm > 0.0 ? settings.contact_margin_mm : 0.25 * thickness;
      options.skin_mm = thickness;
      // Default exclusion 2.5 thickness >= the candidate-list radius (thickness + margin +
      // skin), so that the flat neighbourhood of a vertex on its own sheet never enters the
      // list (see contact.h).
      options.exclusion_radius_mm =
          settings.contact_exclusion_mm > 0.0
              ? settings.contact_exclusion_mm
              : std::max(2.5 * thickness,
                         options.thickness_mm + options.margin_mm + options.skin_mm);
      Eigen::MatrixXi edges = uniqueEdges(model.F);
      if (usesEdgeContactOnEdges(settings, model.V_rest, edges, thickness)) {
        // Contact points: the vertices, then the edge midpoints (index n_ + e).
        contact_edges_ = std::move(edges);
        Eigen::MatrixXd points(n_ + contact_edges_.rows(), 3);
        points.topRows(n_) = model.V_rest;
        for (Eigen::Index e = 0; e < contact_edges_.rows(); ++e) {
          points.row(n_ + e) = 0.5 * (model.V_rest.row(contact_edges_(e, 0)) +
                                      model.V_rest.row(contact_edges_(e, 1)));
        }
        detector_ = std::make_unique<ContactDetector>(points, model.F, options);
        // Inverse masses are fixed for the run: the midpoints' once, (w_i + w_j) / 4.
        points_w_.assign(sys_.w.begin(), sys_.w.end());
        points_w_.resize(n_ + contact_edges_.rows());
        for (Eigen::Index e = 0; e < contact_edges_.rows(); ++e) {
          points_w_[n_ + e] = 0.25 * (sys_.w[contact_edges_(e, 0)] + sys_.w[contact_edges_(e, 1)]);
        }
      } else {
        detector_ = std::make_unique<ContactDetector>(model.V_rest, model.F, options);
      }
    }
  }

  // Edge midpoints are a backstop against sheets crossing edge through edge; the vertices set
  // the separation. At the full thickness the midpoints of a coapting zone fight the vertex
  // contacts, and the default 620-vertex valve took 1,734 steps to settle instead of 516; at
  // 0.8 of it, 508, and every one of the benchmark's 19 crossing closures ends crossing-free
  // (0.7 left one pair on a parametric flap, 0.9 unsettled 5 of the 19; docs/performance.md,
  // "Self-intersections of coarse closures").
  static constexpr double kEdgeContactThicknessFraction = 0.8;

  // With edge contact: positions extended by the edge midpoints, for the detector.
  void extendByMidpoints(const std::vector<double>& x, std::vector<double>& out) const {
    out.resize(3 * static_cast<size_t>(n_ + contact_edges_.rows()));
    std::copy(x.begin(), x.end(), out.begin());
    for (Eigen::Index e = 0; e < contact_edges_.rows(); ++e) {
      const int i = contact_edges_(e, 0), j = contact_edges_(e, 1);
      for (int d = 0; d < 3; ++d) out[3 * (n_ + e) + d] = 0.5 * (x[3 * i + d] + x[3 * j + d]);
    }
  }

  void detectContacts() {
    if (contact_edges_.rows() == 0) {
      detector_->detect(x_prev_.data(), x_.data(), sys_.w.data(), contacts_, team_.get());
      return;
    }
    extendByMidpoints(x_prev_, points_prev_);
    extendByMidpoints(x_, points_);
    detector_->detect(points_prev_.data(), points_.data(), points_w_.data(), contacts_,
                      team_.get());
    // Midpoints back to their edges; a triangle with an end of the edge is the edge's own sheet
    // (the rest-state exclusion covers it only for edges shorter than twice its radius).
    std::size_t kept = 0;
    for (ContactConstraint k : contacts_) {
      if (k.p >= n_) {
        const Eigen::Index e = k.p - n_;
        k.p = contact_edges_(e, 0);
        k.p2 = contact_edges_(e, 1);
        k.thickness *= kEdgeContactThicknessFraction;
        const auto touches = [&k](int v) { return v == k.a || v == k.b || v == k.c; };
        if (touches(k.p) || touches(k.p2)) continue;
      }
      contacts_[kept++] = k;
    }
    contacts_.resize(kept);
  }

  // Dirichlet boundary at ramp fraction s: annulus ring and PM tips, start -> end.
  void setBoundary(double s) {
    for (Eigen::Index k = 0; k < model_.fixed.size(); ++k) {
      const int i = model_.fixed(k);
      for (int d = 0; d < 3; ++d)
        x_[3 * i + d] = (1.0 - s) * model_.fixed_start(k, d) + s * model_.fixed_end(k, d);
    }
    for (Eigen::Index k = 0; k < model_.tip_start.rows(); ++k)
      for (int d = 0; d < 3; ++d)
        tips_[3 * k + d] = (1.0 - s) * model_.tip_start(k, d) + s * model_.tip_end(k, d);
  }

  // Velocity decay toward the flow field per step of a drag with time constant drag_time_ms.
  static double dragDecay(double dt, double drag_time_ms) { return std::exp(-dt / drag_time_ms); }
  void setDragTime(double drag_time_ms) { drag_decay_ = dragDecay(dt_, drag_time_ms); }

  // v += dt w f (pressure); drag toward the flow velocity u; x~ = x + dt v + w (impulse +
  // carry contact_impulse) (the last step's constraint impulses: warm start, the contacts'
  // in part, see SimulationSettings::contact_impulse_carry); displacement clamped to max_step.
  void predict(double pressure, const Vec3& u) {
    pressureForces(model_.F, x_.data(), pressure, force_.data(), n_);
    x_prev_ = x_;
    for (int i = 0; i < n_; ++i) {
      if (sys_.w[i] == 0.0) continue;
      Map3 vi(&v_[3 * i]);
      vi += (dt_ * sys_.w[i]) * CMap3(&force_[3 * i]);
      vi = u + drag_decay_ * (vi - u);
      Vec3 disp = dt_ * vi;
      if (warm_) {
        disp += sys_.w[i] * (CMap3(&impulse_[3 * i]) +
                             settings_.contact_impulse_carry * CMap3(&contact_impulse_[3 * i]));
      }
      const double len = disp.norm();
      if (len > max_step_) disp *= max_step_ / len;
      Map3(&x_[3 * i]) += disp;
    }
  }

  // Gauss-Seidel sweeps in a fixed order, hard constraints last and cords at the very end (a
  // cord pulling its vertex into the other leaflet then wins over the contact, by the
  // contact's O(dt^2) softness, instead of stretching). The last sweep accumulates the
  // constraint impulses for the next prediction. Contacts are detected anew each step and
  // start from lambda = 0 (see simulator.h).
  void solve() {
    if (detector_) detectContacts();
    lambda_contacts_.assign(contacts_.size(), 0.0);
    std::fill(lambda_floors_.begin(), lambda_floors_.end(), 0.0);
    if (!warm_) {
      for (auto* l : {&lambda_edges_, &lambda_areas_, &lambda_bends_, &lambda_cords_})
        std::fill(l->begin(), l->end(), 0.0);
    }
    double* x = x_.data();
    const double* w = sys_.w.data();
    for (int it = 0; it < settings_.iterations; ++it) {
      double* acc = nullptr;
      double* contact_acc = nullptr;
      if (warm_ && it == settings_.iterations - 1) {
        std::fill(impulse_.begin(), impulse_.end(), 0.0);
        std::fill(contact_impulse_.begin(), contact_impulse_.end(), 0.0);
        acc = impulse_.data();
        contact_acc = contact_impulse_.data();
      }
      sweepClasses(sys_.edge_classes, [&](int b, int e) {
        projectDistances(&sys_.edges[b], e - b, inv_dt2_, x, w, &lambda_edges_[b], acc);
      });
      sweepClasses(sys_.area_classes, [&](int b, int e) {
        projectAreas(&sys_.areas[b], e - b, inv_dt2_, x, w, &lambda_areas_[b], acc);
      });
      sweepClasses(sys_.bend_classes, [&](int b, int e) {
        projectBending(&sys_.bends[b], e - b, inv_dt2_, x, w, &lambda_bends_[b], acc);
      });
      sweepClasses(sys_.floor_classes, [&](int b, int e) {
        projectAreaFloors(&sys_.area_floors[b], e - b, x, w, &lambda_floors_[b], acc);
      });
      projectContacts(contacts_, x, w, lambda_contacts_.data(), contact_acc);
      projectCords(sys_.cords, inv_dt2_, tips_.data(), x, w, lambda_cords_.data(), acc,
                   max_cord_pull_);
    }
    // Area floors are checked every sweep but not counted: ns per projection stays comparable
    // with the measurements made before the floor existed (docs/performance.md), and can
    // only come out higher.
    projections_ +=
        static_cast<long long>(settings_.iterations) *
        static_cast<long long>(sys_.edges.size() + sys_.areas.size() + sys_.bends.size() +
                               sys_.cords.size() + contacts_.size());
  }

  // Projects the colour classes in order, project(begin, end) on a range of one class. With a
  // team, each class of at least kMinParallelClass constraints is cut into one part per thread:
  // its constraints share no vertex (nor an acc entry), so the parts can run at the same time
  // and the result is bit-identical to the sequential sweep. Smaller classes, and a shared last
  // class, run on the calling thread, consecutive ones in one call.
  template <class Project>
  void sweepClasses(const ColourClasses& classes, Project project) {
    int serial_begin = classes.starts.front();
    for (int k = 0; k < classes.count(); ++k) {
      const int b = classes.starts[k], e = classes.starts[k + 1];
      const bool shared = classes.last_shared && k + 1 == classes.count();
      if (!team_ || e - b < kMinParallelClass || shared) continue;
      if (serial_begin < b) project(serial_begin, b);
      auto part = [&](int p) {
        int pb, pe;
        partRange(e - b, team_->threads(), p, pb, pe);
        if (pb < pe) project(b + pb, b + pe);
      };
      team_->run(part);
      serial_begin = e;
    }
    if (serial_begin < classes.starts.back()) project(serial_begin, classes.starts.back());
  }

  // v = (x - x_prev) / dt. Returns the largest vertex displacement of the step, or -1 when a
  // position is non-finite or farther than `explode` from `centre`.
  double update(const Vec3& centre, double explode) {
    double max_disp2 = 0.0;
    bool diverged = false;
    for (int i = 0; i < n_; ++i) {
      if (sys_.w[i] == 0.0) continue;
      const Vec3 dx = CMap3(&x_[3 * i]) - CMap3(&x_prev_[3 * i]);
      Map3 vi(&v_[3 * i]);
      vi = dx / dt_;
      max_disp2 = std::max(max_disp2, dx.squaredNorm());
      const double r2 = (CMap3(&x_[3 * i]) - centre).squaredNorm();
      if (!(r2 <= explode * explode)) diverged = true;  // also catches NaN
    }
    return diverged || !std::isfinite(max_disp2) ? -1.0 : std::sqrt(max_disp2);
  }

  int contactCount() const { return static_cast<int>(contacts_.size()); }

  // Total area of the sheet now (metrics.h), on a copy of the positions: called every
  // kAreaCheckEvery steps only.
  double sheetArea() const {
    using Positions = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
    return surfaceArea(Eigen::Map<const Positions>(x_.data(), n_, 3), model_.F);
  }

  // Kinetic energy sum_i m_i |v_i|^2 / 2 of the free vertices (fictitious masses included).
  double kineticEnergy() const {
    double e = 0.0;
    for (int i = 0; i < n_; ++i)
      if (sys_.w[i] > 0.0) e += CMap3(&v_[3 * i]).squaredNorm() / sys_.w[i];
    return 0.5 * e;
  }

  // Kinetic damping (dynamic relaxation): all velocities to zero.
  void stop() { std::fill(v_.begin(), v_.end(), 0.0); }

  // sum += positions of the free vertices (for the mean of an unsettled closure).
  void addFreePositions(std::vector<double>& sum) const {
    for (int i = 0; i < n_; ++i)
      if (sys_.w[i] != 0.0)
        for (int d = 0; d < 3; ++d) sum[3 * i + d] += x_[3 * i + d];
  }

  // The free vertices of result.V replaced by sum / count (Dirichlet vertices keep their
  // exact final positions).
  void setFreePositionsToMean(const std::vector<double>& sum, int count,
                              SimulationResult& result) const {
    for (int i = 0; i < n_; ++i)
      if (sys_.w[i] != 0.0)
        for (int d = 0; d < 3; ++d) result.V(i, d) = sum[3 * i + d] / count;
  }

  // Copies the final state into `result`.
  void finish(SimulationResult& result) const {
    result.projections = projections_;
    result.threads_gave_up = team_ && team_->alone();
    if (detector_) {
      result.contact_rebuilds = detector_->rebuilds();
      result.edge_contact = contact_edges_.rows() > 0;
      result.contact_candidates = detector_->candidates();
    }
    result.V.resize(n_, 3);
    for (int i = 0; i < n_; ++i)
      for (int d = 0; d < 3; ++d) result.V(i, d) = x_[3 * i + d];
    const Eigen::Index num_tips = model_.tip_start.rows();
    result.tips.resize(num_tips, 3);
    for (Eigen::Index k = 0; k < num_tips; ++k)
      for (int d = 0; d < 3; ++d) result.tips(k, d) = tips_[3 * k + d];
    result.cord_force.resize(static_cast<Eigen::Index>(sys_.cords.size()));
    for (size_t c = 0; c < sys_.cords.size(); ++c)  // lambda / dt^2 is the force (N)
      result.cord_force(static_cast<Eigen::Index>(c)) = -lambda_cords_[c] * inv_dt2_;
    result.contacts = 0;
    for (double l : lambda_contacts_) result.contacts += l > 0.0 ? 1 : 0;
  }

  long long projections() const { return projections_; }

 private:
  const SimulationModel& model_;
  const SimulationSettings& settings_;
  const System sys_;
  const int n_;
  const double dt_, inv_dt2_, max_step_, max_cord_pull_;
  double drag_decay_;
  const bool warm_;
  std::vector<double> x_, x_prev_, v_, force_;
  std::vector<double> impulse_;          // sum_j grad C_j lambda_j per vertex (warm start)
  std::vector<double> contact_impulse_;  // the same sum over the contacts alone
  std::vector<double> tips_;             // 3 #tips
  std::vector<double> lambda_edges_, lambda_areas_, lambda_bends_, lambda_cords_, lambda_contacts_;
  std::vector<double> lambda_floors_;  // area floors: from 0 every step, like the contacts
  std::vector<ContactConstraint> contacts_;
  std::unique_ptr<ContactDetector> detector_;
  // Edge contact only: the mesh edges whose midpoints are contact points, and the detector's
  // extended positions and inverse masses (vertices, then midpoints).
  Eigen::MatrixXi contact_edges_;
  std::vector<double> points_prev_, points_, points_w_;
  long long projections_ = 0;
  // Threads of the colour-parallel sweeps (SimulationSettings::threads > 1), else none.
  std::unique_ptr<SweepTeam> team_;
  // Smallest colour class split between threads: 128 constraints are 3-6 us of projections,
  // several times a barrier's round trip between two running cores. Not tuned: the 506-vertex
  // valve, whose classes hold ~150-1,000, gains nothing from two threads, the ~2,000-vertex one
  // 1.26-1.40x (docs/performance.md, "Two threads").
  static constexpr int kMinParallelClass = 128;
};

// The time step: settings.dt_ms, or 0 = the one that gives the median vertex the stiffness
// ratio k_i dt^2 / m_i = stiffness_ratio, no longer than the step of the same mesh with the
// default tissue's modulus. k_i scales with E, so a softer tissue would get a step longer by
// sqrt(E_default / E); but the cords and contacts it moves against are as rigid as before, and
// the pressure moves a vertex dt^2 p / (rho h) per step whatever the tissue. Measured on the 21
// cohort cases (edge 2.5 mm, their heuristic cords) at E = 0.5 MPa: 19 settled, median 2,319
// steps with the longer step; 21 settled, median 802 steps with the default tissue's; the
// default valve at 1 MPa ran to the step cap with it and settles in 675 steps without
// (docs/performance.md, "Soft tissue"). The valve's tissue is E times its median regional
// factor: a lesion softer than the rest does not change the step, a uniform factor acts as E.
//
// On a mesh much finer than the tissue is thick the bending hinges carry most of k_i (the
// median vertex's share: 14 % at edge 2.5 mm, 63 % at 0.8, 75 % at 0.6, 87 % at 0.4, 95 % at
// 0.25 mm, 1 mm tissue), and the stiffness ratio of that k_i no longer keeps the closure
// stable: the default valve at edge 0.4 mm moved 0.1-0.2 mm per step early in the ramp, where
// it moves 1e-3 mm with a smaller ratio, and settled only after 11,826 steps; at 0.25 mm (and
// make-case --edge 0.5's truth) it diverged. Why the curved, pressurised sheet loses
// stability there was not traced: a flat clamped disc with a bending share of ~0.97 is stable
// at 4 times the default ratio. So where the median share exceeds 0.8 the ratio is scaled by
// 5 (1 - share): the 0.4 mm valve settles in 6,434 steps, the 0.25 mm one in ~15,000, both
// without the jitter; meshes with a share up to 0.8 (edges down to ~0.5 mm with 1 mm tissue)
// keep their step (docs/performance.md, "Fine meshes").
double timeStepMs(const System& sys, const SimulationSettings& settings) {
  if (settings.dt_ms != 0.0) return settings.dt_ms;
  const double softness =
      std::min(1.0, settings.material.youngs_modulus_mpa * sys.median_tissue_factor /
                        LeafletMaterial{}.youngs_modulus_mpa);
  const double fine_mesh = std::min(1.0, 5.0 * (1.0 - sys.median_bending_share));
  return sys.median_stiffness_over_mass > 0.0
             ? std::sqrt(settings.stiffness_ratio * softness * fine_mesh /
                         sys.median_stiffness_over_mass)
             : 1e-2;
}

}  // namespace

double closureTimeStepMs(const SimulationModel& model, const SimulationSettings& settings) {
  return timeStepMs(buildSystem(model, settings), settings);
}

SimulationResult simulate(const SimulationModel& model, const SimulationSettings& settings,
                          const Eigen::MatrixXd* start) {
  SimulationResult result;
  result.error = validate(model, settings);
  if (result.error.empty() && start &&
      (start->rows() != model.V_rest.rows() || start->cols() != 3 || !start->allFinite()))
    result.error = "start: must be #V by 3 with finite positions";
  if (!result.error.empty()) return result;

  const auto clock_start = std::chrono::steady_clock::now();
  const double cpu_start = threadCpuSeconds();
  System sys = buildSystem(model, settings);
  const double dt = timeStepMs(sys, settings);
  result.dt_ms = dt;
  if (!(dt * dt < std::numeric_limits<double>::infinity())) {
    result.error = "settings: dt_ms = " + std::to_string(dt) + " is out of range";
    return result;
  }
  // A cold closure still ramping up at the step cap cannot settle; with the automatic time
  // step this is known only once the model is (settingsProblems checks a given dt_ms).
  if (const std::string problem = rampBeyondStepCap(settings, dt); !start && !problem.empty()) {
    result.error = "settings: max_steps: " + problem;
    return result;
  }
  // Selective mass scaling (as explicit FE codes do to keep their time step; dynamic
  // relaxation uses fictitious masses the same way, Underwood 1983): a vertex whose stiffness
  // ratio k_i dt^2 / m_i exceeds max_stiffness_ratio gets the mass that brings it down to it.
  // Only the path to equilibrium changes, not the equilibrium. Without it the few light,
  // stiff vertices of a graded mesh keep the warm-started Gauss-Seidel from settling.
  if (settings.max_stiffness_ratio > 0.0) {
    for (int i = 0; i < sys.n; ++i) {
      if (sys.w[i] == 0.0) continue;
      const double r = sys.stiffness[i] * dt * dt * sys.w[i];
      if (r > settings.max_stiffness_ratio) {
        sys.w[i] *= settings.max_stiffness_ratio / r;
        ++result.mass_scaled_vertices;
      }
    }
  }
  const double thickness = contactThicknessMm(settings);
  const double max_step = velocityClampMm(settings);
  const double sign = settings.phase == ClosurePhase::kClose ? 1.0 : -1.0;
  const double pressure = sign * mmHgToMpa(settings.pressure_mmhg);
  const Vec3 flow = sign * settings.flow_speed_mm_per_ms * model.flow_direction.normalized();
  const double ramp_ms = start ? 0.0 : settings.ramp_ms;
  // Divergence: a vertex farther than 50 model radii from the centre, or moving more than half
  // a model radius in one step (the prediction moves <= max_step; only a diverging solve
  // jumps that far).
  const Vec3 centre = model.V_rest.colwise().mean().transpose();
  const double radius = (model.V_rest.rowwise() - centre.transpose()).rowwise().norm().maxCoeff();
  const double explode = 50.0 * radius + 100.0;
  const double max_jump = std::max(0.5 * radius, 10.0 * max_step);
  // A result stretched to kMaxAreaGrowth times its rest area is not a state of valve tissue:
  // the linear membrane's strain would be 100 % everywhere (leaflets tear at 20-50 %). Too
  // soft a modulus for the pressure gets there without a position going far or fast (0.001
  // MPa: 5,900 times the area, 457 crossing pairs, reported as a settled result). The result
  // is checked; on the way, every kAreaCheckEvery steps, only a runaway past
  // kRunawayAreaGrowth stops the run early, since a soft sheet can pass 4 times its area and
  // come back (small-normal at 0.045 MPa: 4.3 times at step 200, 2.6 times at the end).
  constexpr double kMaxAreaGrowth = 4.0;
  constexpr double kRunawayAreaGrowth = 10.0;
  constexpr int kAreaCheckEvery = 100;
  const double rest_area = surfaceArea(model.V_rest, model.F);

  Stepper stepper(model, settings, std::move(sys), dt, max_step, thickness,
                  start ? *start : model.V_rest);
  int quiet_steps = 0;
  double last_energy = 0.0;
  const bool warm_closure = start && settings.phase == ClosurePhase::kClose;
  const int max_steps =
      warm_closure ? std::min(settings.max_steps, settings.max_warm_steps) : settings.max_steps;
  // Steps max_steps - average_unsettled_steps + 1 .. max_steps (those after the ramp) are
  // summed; used only if the closure does not settle.
  const int first_averaged = max_steps - settings.average_unsettled_steps + 1;
  const int late_drag_step =
      warm_closure ? settings.late_drag_after_warm_steps : settings.late_drag_after_steps;
  std::vector<double> position_sum;
  int averaged = 0;
  for (int step = 1; step <= max_steps; ++step) {
    const double t = step * dt;
    if (step == late_drag_step) {
      stepper.setDragTime(settings.late_drag_time_ms);
      result.late_drag = true;
    }
    const double s = ramp(t, ramp_ms);
    stepper.setBoundary(s);
    stepper.predict(pressure * s, t < ramp_ms ? flow : Vec3::Zero());
    stepper.solve();
    const double disp = stepper.update(centre, explode);
    result.steps = step;
    result.max_displacement_mm = disp;
    // The first step projects the start state onto the constraints: a cord scaled far below
    // its span there moves its insertion by the whole excess (by up to 1.37 times that for a
    // point between vertices, xpbd_constraints.h), which is the input, not an instability.
    if (disp < 0.0 || (disp > max_jump && step > 1)) {
      result.error = "simulation diverged (non-finite or exploding positions) at step " +
                     std::to_string(step) + "; reduce dt_ms or check the input";
      result.diverged = true;
      break;
    }
    if (step % kAreaCheckEvery == 0) {
      if (const double area = stepper.sheetArea(); area > kRunawayAreaGrowth * rest_area) {
        result.error =
            stretchedSheetError(area, rest_area, "by step " + std::to_string(step), settings);
        result.diverged = true;
        break;
      }
    }
    // Kinetic damping: past the ramp, a drop of the kinetic energy means the motion passed
    // the energy minimum along its path; stopping there starts the next descent from rest.
    if (settings.kinetic_damping && t >= ramp_ms) {
      const double energy = stepper.kineticEnergy();
      if (energy < last_energy) {
        stepper.stop();
        last_energy = 0.0;
        ++result.kinetic_stops;
      } else {
        last_energy = energy;
      }
    }
    // Quasi-static equilibrium: max displacement < tolerance for `window` steps after the ramp.
    quiet_steps = (t >= ramp_ms && disp < settings.tolerance_mm) ? quiet_steps + 1 : 0;
    if (settings.progress && settings.progress_every > 0 && step % settings.progress_every == 0)
      settings.progress({step, t, disp, stepper.contactCount()});
    if (quiet_steps >= settings.window) {
      result.converged = true;
      break;
    }
    if (settings.average_unsettled_steps > 0 && step >= first_averaged && t >= ramp_ms) {
      if (position_sum.empty())
        position_sum.assign(3 * static_cast<size_t>(model.V_rest.rows()), 0.0);
      stepper.addFreePositions(position_sum);
      ++averaged;
    }
  }
  result.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
  result.cpu_seconds = threadCpuSeconds() - cpu_start;
  if (settings.progress)
    settings.progress(
        {result.steps, result.steps * dt, result.max_displacement_mm, stepper.contactCount()});
  if (!result.error.empty()) {
    result.projections = stepper.projections();
    return result;
  }
  stepper.finish(result);
  if (!result.converged && averaged > 0) {
    stepper.setFreePositionsToMean(position_sum, averaged, result);
    result.averaged_steps = averaged;
  }
  if (const double area = surfaceArea(result.V, model.F); area > kMaxAreaGrowth * rest_area) {
    result.error = stretchedSheetError(area, rest_area, "at the end", settings);
    result.diverged = true;
  }
  return result;
}

bool usesEdgeContact(const SimulationSettings& settings, const Eigen::MatrixXd& V_rest,
                     const Eigen::MatrixXi& F, double contact_thickness_mm) {
  return usesEdgeContactOnEdges(settings, V_rest, uniqueEdges(F), contact_thickness_mm);
}

}  // namespace chordfit
