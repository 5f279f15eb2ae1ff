// Synthetic cohort presets (DESIGN §8, issue "Synthetic cohort"): named patients-to-be, each a
// parametric mitral anatomy plus a chordal pathology, and the seeded randomness that turns a
// preset into one patient (a seed is a new patient).
//
// Truth cord scales. A true cord's rest length is the paper's heuristic l0 (an upper bound:
// dist(V, AP) + |V - tip|) times its true scale:
//   normal cord        normal_cord_scale (< 1, calibrated so that normal valves close
//                      without prolapse; see experiments/README.md), times
//                      secondary_cord_factor for secondary cords;
//   pathological cord  up to the segment's peak scale (> 1: elongated beyond the heuristic's
//                      bound), with a raised-cosine profile over the segment (below);
//   every cord         x (1 + v), v a smooth random variation of a few percent along the
//                      annulus;
//   ruptured cord      kRupturedCordScale: long enough never to become taut (inert), so truth
//                      and case cords still correspond one to one.
#pragma once

#include <array>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "core/cord_attachments.h"
#include "core/parametric_valve.h"

namespace chordfit {

// Portable seeded random numbers. std::mt19937_64 is fully specified by the standard, but the
// standard distributions are not (libstdc++ and libc++ give different normals), so the
// distributions are written out here: uniform from the top 53 bits, normal by Box-Muller.
class SeededRandom {
 public:
  explicit SeededRandom(std::uint64_t seed) : engine_(seed) {}
  // An independent stream for one purpose (anatomy, cords, tracings, ...): its seed is a
  // splitmix64 mix of (seed, stream), so adding draws to one stream never shifts another.
  static SeededRandom stream(std::uint64_t seed, std::uint64_t stream);

  double uniform();                      // [0, 1), 53 random bits
  double uniform(double lo, double hi);  // [lo, hi)
  // Standard normal by the Box-Muller transform (Box & Muller, Ann. Math. Stat. 1958;29:610):
  //   z0 = sqrt(-2 ln u1) cos(2 pi u2), z1 = sqrt(-2 ln u1) sin(2 pi u2); z1 is kept for the
  //   next call.
  double gaussian();
  // Standard normal clamped to [-limit, limit] (keeps anatomy inside validated ranges).
  double clampedGaussian(double limit);

 private:
  std::mt19937_64 engine_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

// Scale of a normal true cord. Calibrated against the simulator of 2026-11-21 late evening
// (truth edge 1.5 mm, seeds 1-3 of normal-1 and normal-2; experiments/README.md
// "Calibration"): 1.0 prolapses almost everywhere; with secondaries at the same scale
// 0.75-0.85 lets the anterior belly rise above 2 mm; shorter secondaries hold the belly, so
// primaries at 0.8 and secondaries at 0.8 x 0.88 = 0.70 close without prolapse.
constexpr double kNormalCordScale = 0.8;
// Extra factor of secondary (belly) cords relative to primaries (same calibration).
constexpr double kSecondaryCordFactor = 0.88;
// The calibrated normal scale of a cord of this kind: kNormalCordScale, times
// kSecondaryCordFactor for secondaries (the simulator's valve tests use it too).
double normalCordScale(CordKind kind);
// Rest-length scale of a ruptured cord: the cord never becomes taut, so it is inert.
constexpr double kRupturedCordScale = 10.0;

struct CohortPreset {
  std::string name;
  std::string summary;      // one line: what the preset models
  ValveParameters anatomy;  // mean anatomy; target_edge_mm is ignored
  // Rest-length scale of a normal true cord (experiments may override the calibrated value).
  double normal_cord_scale = kNormalCordScale;
  double secondary_cord_factor = kSecondaryCordFactor;
  // Relative SD of each anatomical dimension across seeds (clamped at 2.5 SD).
  double anatomy_sd = 0.04;
  // Pathology: peak true scale of the cords of each Carpentier segment (A1, A2, A3, P1, P2,
  // P3); 0 = normal. It applies to the primary and secondary cords of the segment's leaflet
  // with a raised-cosine profile centred on the segment: a cord at arc fraction f with normal
  // scale s0 gets
  //   s0 + (peak - s0) cos^2(pi (f - c) / w)   for |f - c| < w / 2,   c = (index + 1/2) / 3,
  // so the lesion is densest in the middle of the segment and fades toward its borders.
  std::array<double, 6> segment_scale{0, 0, 0, 0, 0, 0};
  double pathology_width = 1.0 / 3.0;  // w, as a fraction of the leaflet's arc
  // Half-width of the seed-to-seed uniform variation of every peak scale.
  double scale_spread = 0.05;
  // Myxomatous lesion tissue of the true valve: the leaflet's stiffness factor at the centre
  // of every pathological segment (1 = healthy tissue everywhere). It fades with the cords'
  // profile, geometrically: a vertex at arc fraction f gets lesion_stiffness^(cos^2(pi (f - c)
  // / w)) inside the profile and 1 outside. Only the truth has it; the case and the fit assume
  // uniform tissue (a model error the fitter must live with, as with a patient).
  double lesion_stiffness = 1.0;
  // Which pathological segments have the lesion tissue (A1..P3); all false = every segment
  // with a segment_scale.
  std::array<bool, 6> lesion_segments{false, false, false, false, false, false};
  // Flail: this many of the primary cords nearest the middle of `ruptured_segment` rupture
  // (the seed picks a number in [min, max]).
  std::string ruptured_segment;
  int min_ruptured = 0;
  int max_ruptured = 0;
  // Segments where the true closed valve is meant to prolapse (sorted; empty = none).
  std::vector<std::string> intended_prolapse;
};

// All presets in a fixed order: normal-1, normal-2, prolapse-P2, prolapse-A2, prolapse-P3,
// bileaflet, flail-P2.
const std::vector<CohortPreset>& cohortPresets();
// nullptr when unknown.
const CohortPreset* findCohortPreset(const std::string& name);
// "normal-1, normal-2, ..." for messages.
std::string cohortPresetNames();

// Segment id (leaflet * 3 + 0..2) of "A1".."P3"; -1 when not a mitral segment name.
int mitralSegmentId(const std::string& name);

// Whether Carpentier segment `segment` (0..5 = A1..P3) of the preset's truth has lesion tissue:
// lesion_stiffness != 1, the segment is pathological (segment_scale > 0) and listed in
// lesion_segments (or that list is empty).
bool hasLesionTissue(const CohortPreset& preset, int segment);
// Per-vertex tissue stiffness factors of a valve mesh for the preset's lesion (see
// lesion_stiffness; vertices localised by their open-state arc position on their leaflet, as
// the Carpentier segments). Empty when the preset has no lesion tissue.
Eigen::VectorXd lesionTissueStiffness(const CohortPreset& preset, const ValveMesh& mesh);

// One patient's anatomy: every dimension of the preset times (1 + anatomy_sd * z), z a
// clamped standard normal; the closed saddle keeps the preset's closed/open ratio.
ValveParameters samplePatientAnatomy(const CohortPreset& preset, SeededRandom& random);

// The patient's true cord scales, one per attachment (see the file comment). v is a smooth
// random periodic function of the position t in [0, 1) around the whole annulus (anterior arc
// then posterior arc, from the anterolateral commissure):
//   v(t) = sum_{k=1..3} (a_k cos 2 pi k t + b_k sin 2 pi k t) / k,  a_k, b_k ~ N(0, s^2),
// with s chosen so that the SD of v is `variation` (default 3%), clamped to 3 variations.
// `ruptured` (optional) receives one flag per attachment.
std::vector<double> trueCordScales(const CohortPreset& preset,
                                   const std::vector<AnatomicalAttachment>& attachments,
                                   SeededRandom& random, std::vector<bool>* ruptured = nullptr,
                                   double variation = 0.03);

}  // namespace chordfit
