// Preset anatomy sources: normal dimensions as in parametric_valve.cpp (Kaplan et al. 2000;
// Ranganathan et al. 1970). Barlow's disease: dilated annulus (AP ~ 35 mm, CC ~ 40+ mm),
// enlarged, billowing leaflets with elongated cords on both leaflets and a flattened saddle
// (Anyanwu & Adams, Semin Thorac Cardiovasc Surg 2007;19:90; Lee et al., Circ Cardiovasc
// Imaging 2013 report loss of annular saddle shape in bileaflet prolapse).
#include "core/cohort_presets.h"

#include <algorithm>
#include <cmath>

#include "core/carpentier.h"

namespace chordfit {

namespace {

constexpr double kTwoPi = 6.283185307179586;
constexpr double kAnatomyClamp = 2.5;  // SDs
constexpr int kVariationHarmonics = 3;
// Peak true scales of the pathological cords, relative to the heuristic upper bound l0
// (calibrated, experiments/README.md "Calibration"). With the normal cords at 0.8 l0 a
// segment rises above the annulus only once its cords are far longer than the heuristic's
// bound: the elongated cords must let the scallop's free edge swing past the annulus plane.
constexpr double kElongatedP2 = 1.5;
constexpr double kElongatedFlail = 1.4;  // the flail scallop's remaining cords
constexpr double kElongatedBarlow = 2.5;
constexpr double kElongatedA2 = 2.5;
constexpr double kElongatedP3 = 2.5;
// Stiffness factor of the myxomatous lesion tissue of prolapse-A2 and prolapse-P3 at the
// centre of the segment (CohortPreset::lesion_stiffness). Without it neither prolapses, even
// with every cord of the segment inert: the anterior leaflet has no clefts, so A2 cannot rise
// without A1 and A3, and P3 is held by the commissure next to it (experiments/README.md,
// "Calibration"); a softer valve as a whole spreads the prolapse to the commissures. Myxomatous
// leaflets are more extensible than normal ones (Barber et al., J Heart Valve Dis 2001);
// the factors (0.15 and 0.6 MPa against 3) are calibrated, not measured (2026-11-24, edge 3
// mm, seeds 1-3, experiments/README.md "Calibration"): A2 at 0.1, or at 0.05 with the lesion
// only 1/3 of the leaflet wide, left seed 1 below 2 mm. P3 was 0.1 until 2026-11-25 (sixth
// session): with the clefts of 0.8 and the late drag, 0.1 lifts A3 as well on seeds 1-2 at
// edges 2.5 and 1.5 mm, 0.2 prolapses P3 alone on seeds 1-3 at edges 2.5, 2 and 1.5 mm (seed 1
// still lifts A3 at 3 mm).
constexpr double kLesionStiffnessA2 = 0.05;
constexpr double kLesionStiffnessP3 = 0.2;
// Barlow's disease is a myxomatous degeneration (Anyanwu & Adams 2007), so the bileaflet
// truth has lesion tissue in A2, at the A2 factor. Its A2 cords alone cannot lift A2, for the
// reason above: at 2.5, 3.0 and 3.5 x l0 the closure is the same (2026-11-25, edge 3 mm, seeds
// 1-3: A2 at 1.98 / 2.20 / 1.05 mm). With the soft A2 it rises to 3.3 / 3.4 / 2.2 mm; 0.1-0.15
// left seed 3 below 2 mm; a taller or shorter anterior leaflet or a deeper saddle spread it to
// A3 or left it below. P2 prolapses through its cords alone and keeps healthy tissue: soft P2
// as well made the fine truth of seed 3 at the default edge diverge (step 3,828 of its flap;
// experiments/README.md "Calibration").
constexpr double kLesionStiffnessBarlow = 0.05;
// Enlarged prolapsing scallop of the degenerative (myxomatous) anatomy. (Its deep clefts,
// 0.8 of the scallop height against the normal 0.5, became the normal anatomy's on
// 2026-11-25: ValveParameters::indentation_depth.)
constexpr double kEnlargedScallop = 1.2;  // x the normal scallop height

std::uint64_t splitmix64(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

ValveParameters normalAnatomy() { return ValveParameters{}; }

// A second normal patient type: a larger annulus with a flatter saddle and taller leaflets
// (still within normal adult ranges: AP 25-33 mm, A2 20-27 mm, P2 11-17 mm; annular height
// 4-7 mm closed). A deeper saddle (6 -> 8.5 mm) made the anterior belly of this larger valve
// rise above the low commissural hinge line (the prolapse criterion of core/metrics.h) at any
// cord scale the fit can reach (experiments/README.md "Calibration"); with the cords at their
// anatomical points (2faadd7) the saddle 4.5 -> 6.5 mm and A2 25 mm still let it reach
// 2.0-2.5 mm on seeds 1-2. Shorter cords would hold it (0.77 l0) but put the true
// secondaries below the fit's lower scale bound 0.7; 3.7 -> 5.35 mm and A2 24 mm keep it at
// or below 1.8 mm at edges 1.5-3 mm (2026-11-25).
ValveParameters normal2Anatomy() {
  ValveParameters p;
  p.ap_diameter_mm = 31.0;
  p.cc_diameter_mm = 37.0;
  p.saddle_height_mm = 3.7;
  p.closed_saddle_height_mm = 5.35;
  p.anterior_height_mm = 24.0;
  p.posterior_height_mm = 15.5;
  p.posterior_side_height_mm = 12.0;
  p.commissural_height_mm = 9.0;
  return p;
}

// The normal anatomy with the degenerative change of an isolated P2 lesion: a taller P2 scallop
// (14 -> 16.8 mm; P2 heights above 15 mm are typical of fibroelastic deficiency with redundant P2,
// Carpentier's "Reconstructive valve surgery" 2010).
ValveParameters enlargedP2Anatomy() {
  ValveParameters p = normalAnatomy();
  p.posterior_height_mm *= kEnlargedScallop;
  return p;
}

// Commissures 11 mm (10 until 2026-11-25, ninth session): with 10, seed 2 (AP 34.9 mm, A2
// 29.2 mm) lifted A1 to 2.35 mm beside its A2 at edge 2.5 mm; with 11 the three seeds prolapse
// in A2 and P2 alone at edges 3 and 2.5 mm (A1 1.0 mm on seed 2), also with the 10 ms ramp.
// Tried alongside: closed contraction 0.85/0.95, P1/P3 14/16 mm, clefts 0.6, closed saddle
// 4/5 mm, commissures 9, 10.5, 11.5 (experiments/README.md, "Calibration").
ValveParameters barlowAnatomy() {
  ValveParameters p;
  p.ap_diameter_mm = 34.0;
  p.cc_diameter_mm = 41.0;
  p.saddle_height_mm = 3.5;
  p.closed_saddle_height_mm = 4.5;
  p.anterior_height_mm = 28.0;
  p.posterior_height_mm = 19.0;
  p.posterior_side_height_mm = 15.0;
  p.commissural_height_mm = 11.0;
  return p;
}

std::vector<CohortPreset> buildPresets() {
  std::vector<CohortPreset> presets;
  {
    CohortPreset p;
    p.name = "normal-1";
    p.summary = "normal valve, average adult anatomy (AP 28 mm, CC 35 mm, A2 23 mm, P2 14 mm)";
    p.anatomy = normalAnatomy();
    presets.push_back(p);
  }
  {
    CohortPreset p;
    p.name = "normal-2";
    p.summary =
        "normal valve, larger annulus, flatter saddle, taller leaflets (AP 31, CC 37, A2 24, P2 "
        "15.5 mm)";
    p.anatomy = normal2Anatomy();
    presets.push_back(p);
  }
  {
    CohortPreset p;
    p.name = "prolapse-P2";
    p.summary = "isolated P2 prolapse: elongated P2 cords, enlarged P2 (16.8 mm)";
    p.anatomy = enlargedP2Anatomy();
    p.segment_scale = {0, 0, 0, 0, kElongatedP2, 0};
    p.intended_prolapse = {"P2"};
    presets.push_back(p);
  }
  {
    CohortPreset p;
    p.name = "prolapse-A2";
    p.summary = "isolated A2 prolapse: elongated A2 cords, soft (myxomatous) A2 tissue";
    p.anatomy = normalAnatomy();
    p.segment_scale = {0, kElongatedA2, 0, 0, 0, 0};
    p.pathology_width = 0.5;  // the lesion must reach the A2 border to free the free edge
    p.lesion_stiffness = kLesionStiffnessA2;
    p.intended_prolapse = {"A2"};
    presets.push_back(p);
  }
  {
    CohortPreset p;
    p.name = "prolapse-P3";
    p.summary =
        "commissural prolapse: elongated P3 cords (posteromedial side), soft (myxomatous) P3 "
        "tissue";
    p.anatomy = normalAnatomy();
    p.segment_scale = {0, 0, 0, 0, 0, kElongatedP3};
    p.lesion_stiffness = kLesionStiffnessP3;
    p.intended_prolapse = {"P3"};
    presets.push_back(p);
  }
  {
    CohortPreset p;
    p.name = "bileaflet";
    p.summary =
        "Barlow-like bileaflet prolapse: dilated flat annulus, enlarged leaflets, elongated A2 "
        "and P2 cords, soft (myxomatous) A2 tissue";
    p.anatomy = barlowAnatomy();
    p.segment_scale = {0, kElongatedBarlow, 0, 0, kElongatedBarlow, 0};
    p.pathology_width = 0.5;
    p.lesion_stiffness = kLesionStiffnessBarlow;
    p.lesion_segments = {false, true, false, false, false, false};  // A2
    p.intended_prolapse = {"A2", "P2"};
    presets.push_back(p);
  }
  {
    CohortPreset p;
    p.name = "flail-P2";
    p.summary =
        "flail P2: one or two ruptured primary cords in the middle of an elongated, enlarged P2";
    p.anatomy = enlargedP2Anatomy();
    p.segment_scale = {0, 0, 0, 0, kElongatedFlail, 0};
    p.ruptured_segment = "P2";
    p.min_ruptured = 1;
    p.max_ruptured = 2;
    p.intended_prolapse = {"P2"};
    presets.push_back(p);
  }
  return presets;
}

// Weight of the pathology of `segment` at arc fraction f of its leaflet: the raised cosine
// cos^2(pi (f - c) / w) for |f - c| < w / 2 (c the segment's centre, w the pathology width),
// else 0.
double lesionProfile(const CohortPreset& preset, int segment, double fraction) {
  const double offset = fraction - ((segment % 3) + 0.5) / 3.0;
  if (std::abs(offset) >= 0.5 * preset.pathology_width) return 0.0;
  const double bump = std::cos(kTwoPi * 0.5 * offset / preset.pathology_width);
  return bump * bump;
}

double vary(double value, double sd, SeededRandom& random) {
  return value * (1.0 + sd * random.clampedGaussian(kAnatomyClamp));
}

// Position around the whole annulus in [0, 1): anterior arc from the anterolateral commissure
// (t = 0) to the posteromedial one (t = share), then the posterior arc back (t -> 1).
double loopPosition(const AnatomicalAttachment& a, double anterior_share) {
  return a.leaflet == 0 ? a.fraction * anterior_share
                        : anterior_share + (1.0 - a.fraction) * (1.0 - anterior_share);
}

}  // namespace

double normalCordScale(CordKind kind) {
  return kNormalCordScale * (kind == CordKind::kSecondary ? kSecondaryCordFactor : 1.0);
}

SeededRandom SeededRandom::stream(std::uint64_t seed, std::uint64_t stream) {
  return SeededRandom(splitmix64(seed ^ splitmix64(stream + 0x5851F42D4C957F2Dull)));
}

double SeededRandom::uniform() {
  return static_cast<double>(engine_() >> 11) * (1.0 / 9007199254740992.0);  // 2^-53
}

double SeededRandom::uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

double SeededRandom::gaussian() {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  const double u1 = 1.0 - uniform();  // (0, 1]: log is finite
  const double u2 = uniform();
  const double r = std::sqrt(-2.0 * std::log(u1));
  spare_ = r * std::sin(kTwoPi * u2);
  has_spare_ = true;
  return r * std::cos(kTwoPi * u2);
}

double SeededRandom::clampedGaussian(double limit) { return std::clamp(gaussian(), -limit, limit); }

const std::vector<CohortPreset>& cohortPresets() {
  static const std::vector<CohortPreset> presets = buildPresets();
  return presets;
}

const CohortPreset* findCohortPreset(const std::string& name) {
  for (const CohortPreset& p : cohortPresets()) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

std::string cohortPresetNames() {
  std::string names;
  for (const CohortPreset& p : cohortPresets()) {
    names += (names.empty() ? "" : ", ") + p.name;
  }
  return names;
}

int mitralSegmentId(const std::string& name) {
  if (name.size() != 2 || (name[0] != 'A' && name[0] != 'P') || name[1] < '1' || name[1] > '3') {
    return -1;
  }
  return (name[0] == 'A' ? 0 : 3) + (name[1] - '1');
}

ValveParameters samplePatientAnatomy(const CohortPreset& preset, SeededRandom& random) {
  const ValveParameters& mean = preset.anatomy;
  const double sd = preset.anatomy_sd;
  ValveParameters p = mean;
  p.ap_diameter_mm = vary(mean.ap_diameter_mm, sd, random);
  p.cc_diameter_mm = vary(mean.cc_diameter_mm, sd, random);
  p.saddle_height_mm = vary(mean.saddle_height_mm, 2.0 * sd, random);
  p.closed_saddle_height_mm =
      mean.saddle_height_mm > 0.0
          ? p.saddle_height_mm * mean.closed_saddle_height_mm / mean.saddle_height_mm
          : mean.closed_saddle_height_mm;
  p.anterior_height_mm = vary(mean.anterior_height_mm, sd, random);
  p.posterior_height_mm = vary(mean.posterior_height_mm, sd, random);
  p.posterior_side_height_mm = vary(mean.posterior_side_height_mm, sd, random);
  p.commissural_height_mm = vary(mean.commissural_height_mm, sd, random);
  return p;
}

std::vector<double> trueCordScales(const CohortPreset& preset,
                                   const std::vector<AnatomicalAttachment>& attachments,
                                   SeededRandom& random, std::vector<bool>* ruptured,
                                   double variation) {
  // Smooth variation: E[v^2] = s^2 sum_k 1/k^2 over the harmonics.
  double harmonic_weight = 0.0;
  for (int k = 1; k <= kVariationHarmonics; ++k) harmonic_weight += 1.0 / (k * k);
  const double s = variation / std::sqrt(harmonic_weight);
  double a[kVariationHarmonics], b[kVariationHarmonics];
  for (int k = 0; k < kVariationHarmonics; ++k) {
    a[k] = s * random.gaussian();
    b[k] = s * random.gaussian();
  }
  std::array<double, 6> peak = preset.segment_scale;
  for (double& f : peak) {
    const double jitter = random.uniform(-preset.scale_spread, preset.scale_spread);
    if (f > 0.0) f += jitter;
  }
  const double draw = random.uniform();
  const int rupture_count =
      preset.max_ruptured > 0
          ? preset.min_ruptured +
                std::min(preset.max_ruptured - preset.min_ruptured,
                         static_cast<int>(draw * (preset.max_ruptured - preset.min_ruptured + 1)))
          : 0;

  std::vector<double> scales;
  for (const AnatomicalAttachment& att : attachments) {
    const double t = loopPosition(att, preset.anatomy.anterior_fraction);
    double v = 0.0;
    for (int k = 1; k <= kVariationHarmonics; ++k) {
      v += (a[k - 1] * std::cos(kTwoPi * k * t) + b[k - 1] * std::sin(kTwoPi * k * t)) / k;
    }
    v = std::clamp(v, -3.0 * variation, 3.0 * variation);
    double scale = preset.normal_cord_scale *
                   (att.kind == CordKind::kSecondary ? preset.secondary_cord_factor : 1.0);
    for (int segment = 0; segment < 6; ++segment) {
      if (peak[segment] <= 0.0 || segment / 3 != att.leaflet) continue;
      scale += (peak[segment] - scale) * lesionProfile(preset, segment, att.fraction);
    }
    scales.push_back(scale * (1.0 + v));
  }

  std::vector<bool> flags(attachments.size(), false);
  const int segment = mitralSegmentId(preset.ruptured_segment);
  if (segment >= 0 && rupture_count > 0) {
    const double centre = ((segment % 3) + 0.5) / 3.0;
    std::vector<std::size_t> candidates;
    for (std::size_t i = 0; i < attachments.size(); ++i) {
      if (attachments[i].kind == CordKind::kPrimary && attachments[i].segment() == segment) {
        candidates.push_back(i);
      }
    }
    std::stable_sort(candidates.begin(), candidates.end(), [&](std::size_t x, std::size_t y) {
      return std::abs(attachments[x].fraction - centre) <
             std::abs(attachments[y].fraction - centre);
    });
    for (int r = 0; r < rupture_count && r < static_cast<int>(candidates.size()); ++r) {
      flags[candidates[r]] = true;
      scales[candidates[r]] = kRupturedCordScale;
    }
  }
  if (ruptured) *ruptured = flags;
  return scales;
}

bool hasLesionTissue(const CohortPreset& preset, int segment) {
  const bool every_segment = std::none_of(preset.lesion_segments.begin(),
                                          preset.lesion_segments.end(), [](bool on) { return on; });
  return preset.lesion_stiffness != 1.0 && preset.segment_scale[segment] > 0.0 &&
         (every_segment || preset.lesion_segments[segment]);
}

Eigen::VectorXd lesionTissueStiffness(const CohortPreset& preset, const ValveMesh& mesh) {
  if (preset.lesion_stiffness == 1.0) return {};
  const SegmentMap map = openStateSegmentMap(mesh);
  Eigen::VectorXd factors = Eigen::VectorXd::Ones(mesh.V.rows());
  for (Eigen::Index v = 0; v < mesh.V.rows(); ++v) {
    const ArcPosition at = arcPositionOf(map, mesh.V.row(v).transpose(), mesh.leaflet(v));
    if (at.leaflet < 0 || at.leaflet > 1) continue;  // mitral presets: two leaflets
    double weight = 0.0;                             // the strongest lesion reaching this vertex
    for (int segment = at.leaflet * 3; segment < at.leaflet * 3 + 3; ++segment) {
      if (hasLesionTissue(preset, segment))
        weight = std::max(weight, lesionProfile(preset, segment, at.fraction));
    }
    factors(v) = std::pow(preset.lesion_stiffness, weight);
  }
  return factors;
}

}  // namespace chordfit
