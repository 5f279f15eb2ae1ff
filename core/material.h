// Physical parameters of the valve and their conversion to simulator quantities. This is the
// ONE place where units are converted (DESIGN §3).
//
// Internal unit system of the simulator (consistent, no hidden factors):
//   length  mm
//   mass    g
//   time    ms
//   force   N        (g mm / ms^2 = 1e-3 kg * 1e-3 m / 1e-6 s^2 = 1 N)
//   stress, pressure  MPa = N/mm^2
//   energy  mJ = N mm
// so Young's modulus in MPa and thickness in mm are used as given, a cord compliance in mm/N
// (Cord::compliance) is already internal, a pressure in mmHg is multiplied by
// kMpaPerMmHg and a density in g/cm^3 by kGramPerMm3PerGramPerCm3.
//
// Compliance mapping (XPBD compliance alpha = 1 / stiffness of the constraint's quadratic
// energy E = C^2 / (2 alpha), Macklin et al. 2016):
//   - stretching: per mesh edge e a spring C = |xi - xj| - l0 with stiffness
//       k_e = s * E h * sum_{T adjacent to e} A_T / l0^2          [N/mm]
//     (Van Gelder 1998, "Approximate simulation of elastic membranes by triangulated spring
//     meshes", J. Graphics Tools 3(2)). On an equilateral mesh s = 1 reproduces a 2D Young's
//     modulus Y = E h with Poisson ratio 1/3 (triangular spring lattice: lambda = mu =
//     sqrt(3)/4 k).
//   - area: per triangle C = A - A0 with stiffness K_a / A0, K_a = area_bulk_fraction * E h:
//     an extra 2D bulk modulus (paper: "area conservation constraints"). It raises lambda, so
//     the springs are scaled by s (< 1) such that the combined lattice keeps Y = E h:
//       Y = 4 c (2 c + K_a) / (3 c + K_a),  c = s (3/8) E h   (2D Lame, lambda = c + K_a, mu = c)
//     The effective in-plane Poisson ratio is (c + K_a) / (3 c + K_a) (1/3 without area term).
//   - bending: per interior edge C = theta - theta0 (dihedral angle, rad) with stiffness
//       k_b = f D l0^2 / (A1 + A2),   D = E h^3 / (12 (1 - nu^2))   [N mm]
//     f = flexural_modulus_factor (the flexural modulus f E over the tensile E). Derivation:
//     bend a flat equilateral lattice of edge l into z = x^T S x / 2. The faces are secants,
//     so an edge of direction t and in-plane normal m gets
//       theta = h_t (m^T S m - t^T S t / 3),   h_t = sqrt(3) l / 2 the triangles' height
//     (the surface's rise over each apex's height, less the edge's own sag). Summing
//     k_b theta^2 / 2 over the three edge directions gives the energy per area
//       (f D / 2) [(k1 + k2)^2 - (8/3) k1 k2]             (k1, k2 principal curvatures),
//     a Kirchhoff plate of rigidity f D whose Gauss-curvature term is that of nu = -1/3
//     whatever poisson_ratio says (poisson_ratio enters D only). Cylindrical bending and
//     clamped plates do not see the Gauss term (it integrates to a boundary term that a clamped
//     edge fixes); free edges and curved simply supported edges (the valve's annulus) do.
//     Measured: a simply supported strip
//     bends as Kirchhoff's 5 p L^4 / (384 f D) to 0.2 %, a clamped disc as p a^4 / (64 f D) to
//     ~10 % (tests/test_xpbd_plate.cpp; docs/performance.md, "Bending against Kirchhoff
//     plates"). Grinspun et al. 2003 ("Discrete shells") weight the hinges by |e|^2 / A too.
//   - lumped mass per vertex m_i = rho h A_i / 3 summed over incident triangles [g].
//
// Check: a clamped circular membrane under pressure must match Hencky's solution
// w0 = 0.662 a (p a / (E h))^(1/3) (tests/test_xpbd_hencky.cpp).
#pragma once

namespace chordfit {

constexpr double kMpaPerMmHg = 133.322387415e-6;   // 1 mmHg = 133.322 Pa
constexpr double kGramPerMm3PerGramPerCm3 = 1e-3;  // 1 g/cm^3 = 1e-3 g/mm^3

// Leaflet tissue, isotropic linear elastic membrane + plate bending.
// Defaults: E from the linear anisotropic moduli of Kunzelman et al. 1993 ("Finite element
// analysis of the mitral valve", J Heart Valve Dis 2:326, 1.9 - 6.2 MPa radial /
// circumferential), taken as an isotropic value in that range; thickness ~1 mm (Kunzelman
// 1993: 1.3 mm anterior, 1.3 mm posterior; thinner toward the free edge); density of soft
// tissue ~1.04 - 1.1 g/cm^3.
struct LeafletMaterial {
  double youngs_modulus_mpa = 3.0;
  double thickness_mm = 1.0;
  double poisson_ratio = 0.3;  // enters the bending rigidity D only (see above)
  double density_g_per_cm3 = 1.06;
  double area_bulk_fraction = 0.1;  // K_a / (E h); 0 disables the area constraints
  // Flexural over tensile modulus (bending rigidity f D, above). 2 is what the simulator has
  // used since its start, when the mapping above read k_b = 2 D l0^2 / (A1 + A2) and claimed
  // rigidity D (its theta, 2 h_t m^T S m / 3, is right on a sphere only): the
  // cohort, its calibration and every committed result are made with it, and with 1 the
  // normal truths billow into A3 prolapse (docs/performance.md, "Bending against Kirchhoff
  // plates"). A flexural modulus of 6 MPa is Kunzelman's circumferential tensile modulus.
  double flexural_modulus_factor = 2.0;
};

// Pressure mmHg -> MPa (N/mm^2).
inline double mmHgToMpa(double mmhg) { return mmhg * kMpaPerMmHg; }

// Membrane (2D) Young's modulus Y = E h, N/mm.
double membraneModulus(const LeafletMaterial& m);

// Plate bending rigidity D = E h^3 / (12 (1 - nu^2)) of the tensile modulus, N mm (the
// simulated sheet's is flexural_modulus_factor times this).
double bendingRigidity(const LeafletMaterial& m);

// Spring scale s solving Y = 4c(2c + K_a)/(3c + K_a), c = s (3/8) Y, K_a = f Y (f =
// area_bulk_fraction). s = 1 for f = 0.
double springScale(double area_bulk_fraction);

// Effective in-plane Poisson ratio of springs + area term.
double effectivePoissonRatio(double area_bulk_fraction);

// Compliances (1 / stiffness) in internal units:
//   edge: adjacent_area = sum of rest areas of the triangles sharing the edge (mm^2),
//         rest_length l0 (mm). Returns mm/N.
double edgeCompliance(const LeafletMaterial& m, double adjacent_area, double rest_length);
//   bending: rest_length of the hinge edge, adjacent_area = A1 + A2. Returns 1/(N mm).
double bendingCompliance(const LeafletMaterial& m, double adjacent_area, double rest_length);
//   area: rest_area A0 (mm^2). Returns mm^3/N. Infinity if area_bulk_fraction is 0.
double areaCompliance(const LeafletMaterial& m, double rest_area);

// Lumped vertex mass for a vertex with `vertex_area` = one third of the incident triangle
// areas (mm^2). Returns g.
double lumpedMass(const LeafletMaterial& m, double vertex_area);

}  // namespace chordfit
