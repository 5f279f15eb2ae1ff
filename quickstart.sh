#!/usr/bin/env bash
# chordfit quick start. Two verbs:
#   ./quickstart.sh fit    install what is missing, build, fit the cords of the bundled default case
#   ./quickstart.sh test   install what is missing, build, run the test suite (ctest), then the
#                          benchmark pipeline's smoke run (experiments/smoke.sh)
# Tested on Debian 12 (bookworm). Ubuntu 22.04 ships Ceres 2.0; the build needs Ceres >= 2.1.
# Other releases are untested. Uses sudo when not root.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
build="${CHORDFIT_BUILD_DIR:-$here/build}"
jobs="${CHORDFIT_JOBS:-$(nproc 2>/dev/null || echo 2)}"

packages=(
  build-essential cmake
  libeigen3-dev libceres-dev libnlopt-cxx-dev libcgal-dev
  nlohmann-json3-dev libcli11-dev libgtest-dev libbenchmark-dev
)

say() { printf '\n==> %s\n' "$*"; }

install_missing() {
  local missing=()
  for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [ ${#missing[@]} -eq 0 ]; then
    say "all ${#packages[@]} Debian packages present"
    return
  fi
  say "installing missing packages: ${missing[*]}"
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

build_project() {
  say "configuring and building (Release) in $build with $jobs jobs"
  cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$build" -j "$jobs"
}

run_fit() {
  local exe="$build/tools/chordfit"
  local case_dir="$build/cases/prolapse-P2"
  local out="$here/out/quickstart-fit"
  # The issue's default scale bounds [0.7, 1.5]; CHORDFIT_SCALE_BOUNDS overrides them (a
  # cohort whose true scales lie below 0.7 needs e.g. 0.5,1.5; docs/fitting.md).
  local bounds="${CHORDFIT_SCALE_BOUNDS:-0.7,1.5}"
  say "chordfit fit: per-cord rest-length scales of the bundled case prolapse-P2 (Ceres)"
  echo "      case: $case_dir (synthetic; its truth in truth/ is not read by the fit)"
  echo "      scale bounds: $bounds; outputs: $out"
  # At most 1000 forward runs with warm-started finite differences; Ceres stops on its own
  # tolerance after ~280 (4-7 s on 2 idle cores by machine, docs/fitting.md "Measured results").
  # fit takes at most 64 threads.
  "$exe" fit "$case_dir" --params scales --optimizer ceres --threads "$((jobs < 64 ? jobs : 64))" --fd-warm \
    --max-sims "${CHORDFIT_MAX_SIMS:-1000}" --scale-bounds "$bounds" --out "$out"
  say "seed vs fit (Table 1 layout; the truth's own deviation, the noise floor, for reference)"
  sed -n '/^| Cord set/,/^$/p' "$out/report.md"
  if [ -f "$case_dir/truth/metrics.json" ]; then
    # The true cords' own closure on the truth's finer mesh against the noisy tracings.
    grep -o '"mean_mm": [0-9.]*' "$case_dir/truth/metrics.json" |
      awk '{ printf "      noise floor (the truth'"'"'s AvgD): %.2f mm\n", $2 }'
  fi
  say "done: $out/report.md, sections.svg (fit vs tracings per plane), cords.json, closed.ply / closed.vtk (ParaView, 3D Slicer)"
}

run_tests() {
  say "running the test suite"
  (cd "$build" && ctest --output-on-failure -j "$jobs")
  say "benchmark pipeline smoke run (one case, one seed, small budget; experiments/README.md)"
  "$here/experiments/smoke.sh" "$build"
}

case "${1:-}" in
  fit)  install_missing; build_project; run_fit ;;
  test) install_missing; build_project; run_tests ;;
  *)
    echo "usage: $0 fit|test" >&2
    exit 2
    ;;
esac
