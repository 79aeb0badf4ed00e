#!/usr/bin/env bash
# Surface-area change rate of simplification (the paper's measure of its regional method,
# 0.43 %): reconstruct a mesh from the full cloud and from each simplified cloud with the same
# method (region-growing triangulation), then |A_simplified - A_full| / A_full, next to the
# holes each mesh keeps (a hole lowers the area, so both are printed).
#   bench/simplify/run_area_bench.sh [CLOUD] [RATIOS]
# Defaults: bench/out/armadillo_100000.ply (bench/run_bench.sh makes it; oriented normals from
# the mesh) and ratios "0.1 0.2". Needs BUILD_DIR (default build) with the pointsurf CLI.
# Areas by Open3D 0.16 (/usr/bin/python3). Writes bench/out/area/ and prints a markdown table.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
CLOUD="${1:-$ROOT/bench/out/armadillo_100000.ply}"
RATIOS="${2:-0.1 0.2}"
CLI="$BUILD_DIR/pointsurf"
PY=/usr/bin/python3
WORK="$ROOT/bench/out/area"
mkdir -p "$WORK"
[ -x "$CLI" ] || { echo "error: $CLI is missing; build first" >&2; exit 1; }
[ -f "$CLOUD" ] || { echo "error: $CLOUD is missing (run bench/run_bench.sh first)" >&2; exit 1; }

"$CLI" reconstruct "$CLOUD" "$WORK/full.ply" -q --report "$WORK/full.json"
for ratio in $RATIOS; do
  for method in regional curvature curvature-distance grid random; do
    echo "[area] $method $ratio" >&2
    "$CLI" simplify "$CLOUD" "$WORK/${method}_${ratio}.ply" --method "$method" --ratio "$ratio" -q
    "$CLI" reconstruct "$WORK/${method}_${ratio}.ply" "$WORK/${method}_${ratio}_mesh.ply" -q \
      --report "$WORK/${method}_${ratio}_mesh.json"
  done
done

"$PY" - "$WORK" "$RATIOS" <<'PYEOF'
import json, sys
import open3d as o3d
work, ratios = sys.argv[1], sys.argv[2].split()
def area(path):
    return o3d.io.read_triangle_mesh(path).get_surface_area()
def holes(report):  # the reconstruction stage's hole count and the input's point count
    r = json.load(open(report))
    points = r["inputs"][0]["points"]
    for stage in r["stages"]:
        if "holes" in stage.get("metrics", {}):
            return stage["metrics"]["holes"], points
    return "?", points
full = area(f"{work}/full.ply")
h, n = holes(f"{work}/full.json")
print(f"full cloud: {n} points, mesh area {full:.6g}, {h} holes")
print()
print("| method | ratio | points | mesh area | area change | holes |")
print("|---|---|---|---|---|---|")
for ratio in ratios:
    for method in ("regional", "curvature", "curvature-distance", "grid", "random"):
        a = area(f"{work}/{method}_{ratio}_mesh.ply")
        h, n = holes(f"{work}/{method}_{ratio}_mesh.json")
        print(f"| {method} | {ratio} | {n} | {a:.6g} | {100 * abs(a - full) / full:.2f} % | {h} |")
PYEOF
