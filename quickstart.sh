#!/usr/bin/env bash
# chordfit quick start. Two verbs:
#   ./quickstart.sh fit    install what is missing, build, run the main pipeline on a bundled case
#   ./quickstart.sh test   install what is missing, build, run the whole test suite (ctest)
# Works on a fresh Debian (bookworm) or Ubuntu (22.04+) machine; uses sudo when not root.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
build="${CHORDFIT_BUILD_DIR:-$here/build}"
jobs="${CHORDFIT_JOBS:-$(nproc 2>/dev/null || echo 2)}"

packages=(
  build-essential cmake
  libeigen3-dev libceres-dev libnlopt-cxx-dev libnanoflann-dev libcgal-dev
  nlohmann-json3-dev libcli11-dev libtbb-dev libgtest-dev libbenchmark-dev
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
  local out="$here/out/quickstart"
  local case_dir="$out/case"
  mkdir -p "$out"
  say "NOTE: inverse fitting is not implemented yet. This runs the most complete pipeline"
  echo "      that exists: parametric valve -> validation -> the paper's heuristic chordae"
  echo "      -> XPBD closure -> metrics of the closed valve (the paper's 'heuristic' row)."
  say "1/4 make-valve: parametric mitral valve case -> $case_dir"
  "$exe" make-valve --out "$case_dir" --edge 1.5
  say "2/4 validate"
  "$exe" validate "$case_dir"
  say "3/4 heuristic chordae -> $out/heuristic_cords.json"
  "$exe" heuristic "$case_dir" --out "$out/heuristic_cords.json"
  say "4/4 simulate closure with the heuristic cords -> $out/closed"
  "$exe" simulate "$case_dir" --cords "$out/heuristic_cords.json" --out "$out/closed"
  say "done: outputs in $out (closed.ply / closed.vtk open in ParaView or 3D Slicer)"
}

run_tests() {
  say "running the test suite"
  cd "$build"
  ctest --output-on-failure -j "$jobs"
}

case "${1:-}" in
  fit)  install_missing; build_project; run_fit ;;
  test) install_missing; build_project; run_tests ;;
  *)
    echo "usage: $0 fit|test" >&2
    exit 2
    ;;
esac
