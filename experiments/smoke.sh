#!/usr/bin/env bash
# CI smoke run of the benchmark experiments (issue "Benchmark experiments", item 7): one
# case, one seed, a small forward-simulation budget, every method and every table, from a
# clean directory. Fails when any job fails (e.g. a missing chordfit command), when a table
# lacks a planned row, or when a table's columns differ from the documented ones.
#   usage: experiments/smoke.sh [BUILD_DIR]     (default: build)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
build="${1:-build}"
runner="$build/experiments/run_experiments"
out="$build/experiments/smoke"
[[ -x "$runner" ]] || { echo "smoke: $runner not built (cmake --build $build --target run_experiments)" >&2; exit 2; }
rm -rf "$out"
"$runner" all --smoke --case-source "$build/cases"   # runs, merges and checks (rows and CSV widths); exit != 0 on any failure

# The documented columns (experiments/README.md, "Benchmark experiments"), checked here
# independently of the program that writes them.
expect_header() {
  local file="$out/results/$1" want="$2"
  local got
  got="$(head -n 1 "$file")"
  [[ "$got" == "$want" ]] || { echo "smoke: $1: header '$got', expected '$want'" >&2; exit 1; }
}
expect_header table1.csv "case,preset,seed,method,label,area_mm2,min_mm,median_mm,max_mm,mean_mm,sd_mm,prolapse_reconstructed,section_prolapse_segments,prolapse_segments,tracing_prolapse_segments,forward_sims,wall_seconds"
expect_header acceptance.csv "case,preset,pathological,heuristic_mean_mm,fit_mean_mm,reduction_pct,noise_floor_mean_mm,fit_over_noise_floor,truth_on_case_mesh_mean_mm,tracing_prolapse_segments,fit_section_prolapse_segments,prolapse_reconstructed,fit_tissue_prolapse_segments,tissue_prolapse_reconstructed,intended_prolapse_segments,prolapse_as_intended,cords,ruptured_cords,cords_within_3mm,recovery_median_pct_within_3mm,taut_cords_within_3mm,recovery_median_pct_taut_within_3mm,forward_sims,tissue_retry_kept,wall_seconds"
expect_header optimizers.csv "case,optimizer,budget_sims,final_mean_mm,final_max_mm,forward_sims,sims_to_within_10pct_of_best,wall_seconds"
expect_header recovery.csv "label,attachment_distance,cords,median_abs_error_pct,p90_abs_error_pct"
expect_header sensitivity.csv "sweep,value,case,heuristic_mean_mm,fit_mean_mm,fit_max_mm,noise_floor_mean_mm,recovery_median_pct_all,recovery_median_pct_within_3mm"
for label in heuristic manual-like per-cord per-cord+tips truth "noise floor"; do
  grep -q ",$label," "$out/results/table1.csv" || { echo "smoke: table1.csv: no '$label' row" >&2; exit 1; }
done
# Every fit job records its closures that reached the step cap (summed in the docs).
for job in "$out/results/jobs/"*__fit_*.json; do
  grep -q '"unsettled_sims"' "$job" || { echo "smoke: $job: no unsettled_sims" >&2; exit 1; }
done
for svg in optimizers recovery sensitivity; do
  grep -q "<svg" "$out/results/$svg.svg" || { echo "smoke: $svg.svg is not an SVG" >&2; exit 1; }
done
echo "smoke: benchmark pipeline ok ($out/results)"
