#!/usr/bin/env bash
# Surface-area change rate of simplification (the paper's measure of its regional method,
# 0.43 %), every method against CGAL's hierarchy simplification at equal reduction (the count
# CGAL gives nearest ratio x N): see area_bench.py.
#   bench/simplify/run_area_bench.sh [RATIOS] [NAME ...]
# Inputs (NAME): b9 (CGAL's aerial LiDAR tile, normals by `pointsurf normals --orient mst`),
# building (CGAL's facade scan with its own normals), and area-uniform samples with mesh normals
# of CGAL's armadillo (100k), fandisk (50k), bull (100k) and elephant (100k). Default: all six,
# ratios "0.1".
# Needs BUILD_DIR (default build) with pointsurf and bench/pointsurf_bench; compiles the CGAL
# peer. Areas by Open3D 0.16 (/usr/bin/python3). Writes bench/out/area/, appends raw rows to
# bench/results/simplify_area.csv and prints a markdown table per input.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
RATIOS="${1:-0.1}"
shift || true
NAMES="${*:-b9 building armadillo fandisk bull elephant}"
CLI="$BUILD_DIR/pointsurf"
SAMPLER="$BUILD_DIR/bench/pointsurf_bench"
PY=/usr/bin/python3
WORK="$ROOT/bench/out/area"
DATA="$ROOT/bench/out/cgaldata"
CGAL_BIN="$WORK/cgal_hierarchy"
mkdir -p "$WORK" "$DATA"
for tool in "$CLI" "$SAMPLER"; do [ -x "$tool" ] || { echo "error: $tool is missing; build first" >&2; exit 1; }; done
if [ ! -x "$CGAL_BIN" ] || [ "$ROOT/bench/simplify/cgal_hierarchy.cpp" -nt "$CGAL_BIN" ]; then
  g++ -O2 -std=c++17 -DNDEBUG -DCGAL_EIGEN3_ENABLED -I/usr/include/eigen3 "$ROOT/bench/simplify/cgal_hierarchy.cpp" \
    -o "$CGAL_BIN" -lgmp -lmpfr
fi
[ -d "$DATA/data" ] || tar -xzf /usr/share/doc/libcgal-demo/data.tar.gz -C "$DATA"
inputs=()
for name in $NAMES; do
  cloud="$WORK/input_$name.ply"
  if [ ! -f "$cloud" ]; then
    case "$name" in
      b9) "$CLI" normals "$ROOT/data/b9_training.ply" "$cloud" --orient mst -q ;;
      building) cp "$DATA/data/points_3/building.ply" "$cloud" ;;
      armadillo | bull | elephant) "$SAMPLER" sample "$DATA/data/meshes/$name.off" 100000 "$cloud" 1 ;;
      fandisk) "$SAMPLER" sample "$DATA/data/meshes/$name.off" 50000 "$cloud" 1 ;;
      *) echo "error: unknown input $name (b9 building armadillo fandisk bull elephant)" >&2; exit 1 ;;
    esac
  fi
  inputs+=("$name=$cloud")
done
cd "$ROOT"
"$PY" "$ROOT/bench/simplify/area_bench.py" "$CLI" "$CGAL_BIN" "$WORK" "$ROOT/bench/results/simplify_area.csv" "$RATIOS" "${inputs[@]}"
