#!/usr/bin/env bash
# Simplification benchmark, pointsurf next to its peers in the same run:
#   1. grid (voxel centroid) against Open3D 0.16 voxel_down_sample, same cell, same output;
#   2. the paper's chain, statistical outlier removal + regional simplification to 10 %, with
#      one shared kd-tree (simplify_runner pipeline; the issue's target is 0.3 s at 100k);
#   3. regional against CGAL's hierarchy_simplify_point_set (Pauly et al. 2002) at the output
#      size CGAL chose: time, and Chamfer / Hausdorff of each result to the full cloud.
#   bench/simplify/run_simplify_bench.sh [SIZES] [REPEATS]     (default: "100000 1000000" 5)
# Inputs: the armadillo clouds of bench/run_bench.sh (bench/out/armadillo_N.ply); a size whose
# cloud is missing is skipped with a message. Medians of REPEATS runs; each run alternates the
# tools so that load from elsewhere hits both. Needs BUILD_DIR (default build) configured with
# -DPOINTSURF_BUILD_BENCHMARKS=ON and bench/simplify_runner plus pointsurf built; compiles the
# CGAL peer. Writes bench/out/simplify/results.jsonl and prints a markdown table.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
SIZES="${1:-100000 1000000}"
REPEATS="${2:-5}"
PY=/usr/bin/python3
RUNNER="$BUILD_DIR/bench/simplify_runner"
CLI="$BUILD_DIR/pointsurf"
WORK="$ROOT/bench/out/simplify"
CGAL_BIN="$WORK/cgal_hierarchy"
mkdir -p "$WORK"
for tool in "$RUNNER" "$CLI"; do
  [ -x "$tool" ] || { echo "error: $tool is missing; build with -DPOINTSURF_BUILD_BENCHMARKS=ON" >&2; exit 1; }
done
if [ ! -x "$CGAL_BIN" ] || [ "$ROOT/bench/simplify/cgal_hierarchy.cpp" -nt "$CGAL_BIN" ]; then
  g++ -O2 -std=c++17 -DNDEBUG -DCGAL_EIGEN3_ENABLED -I/usr/include/eigen3 "$ROOT/bench/simplify/cgal_hierarchy.cpp" \
    -o "$CGAL_BIN" -lgmp -lmpfr
fi

RESULTS="$WORK/results.jsonl"
: > "$RESULTS"
tag() {  # case, then a JSON line on stdin -> results
  "$PY" -c 'import json,sys; d=json.loads(sys.stdin.read()); d["case"]=sys.argv[1]; print(json.dumps(d))' "$1" >> "$RESULTS"
}

for n in $SIZES; do
  cloud="$ROOT/bench/out/armadillo_${n}.ply"
  if [ ! -f "$cloud" ]; then echo "skip: $cloud missing (run bench/run_bench.sh first)" >&2; continue; fi
  name="armadillo_${n}"
  # Grid: a cell of about 3 mean spacings (the CLI reports the spacing).
  spacing=$("$CLI" info "$cloud" --json 2>/dev/null | "$PY" -c 'import json,sys; print(json.load(sys.stdin).get("mean_spacing", 0))' || echo 0)
  cell=$("$PY" -c "import sys; s=float(sys.argv[1]); print(3*s if s>0 else 1.0)" "$spacing")
  for ((r = 0; r < REPEATS; r++)); do
    echo "[$name] grid cell $cell run $((r + 1))/$REPEATS" >&2
    "$RUNNER" grid "$cloud" "$cell" | tag "$name"
    "$PY" "$ROOT/bench/simplify/open3d_simplify.py" "$cloud" "$cell" | tag "$name"
  done
  if [ "$n" -le 100000 ]; then
    echo "[$name] sor + regional pipeline x$REPEATS" >&2
    "$RUNNER" pipeline "$cloud" 0.1 "$REPEATS" | tag "$name"
  fi
  # Regional against CGAL's hierarchy simplification at CGAL's output size.
  "$CLI" convert "$cloud" "$WORK/${name}_full.xyz" >/dev/null  # positions only for CGAL's reader
  awk '{print $1, $2, $3}' "$WORK/${name}_full.xyz" > "$WORK/$name.xyz"
  for ((r = 0; r < REPEATS; r++)); do
    echo "[$name] cgal hierarchy run $((r + 1))/$REPEATS" >&2
    "$CGAL_BIN" "$WORK/$name.xyz" 10 0.333 "$WORK/${name}_cgal.xyz" | tag "$name"
  done
  cgal_count=$(wc -l < "$WORK/${name}_cgal.xyz")
  ratio=$("$PY" -c "print($cgal_count / $n)")
  for ((r = 0; r < REPEATS; r++)); do
    echo "[$name] regional ratio $ratio run $((r + 1))/$REPEATS" >&2
    "$RUNNER" regional "$cloud" "$ratio" "$WORK/${name}_regional.ply" | tag "$name"
  done
  "$RUNNER" quality "$cloud" "$WORK/${name}_cgal.xyz" | "$PY" -c \
    'import json,sys; d=json.loads(sys.stdin.read()); d.update(tool="cgal", stage="hierarchy-quality"); print(json.dumps(d))' | tag "$name"
done

"$PY" - "$RESULTS" <<'PYEOF'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
def med(case, tool, stage, key="seconds"):
    v = [r[key] for r in rows if r.get("case") == case and r.get("tool") == tool and r.get("stage") == stage and key in r]
    return statistics.median(v) if v else None
cases = sorted({r["case"] for r in rows}, key=lambda c: int(c.split("_")[-1]))
print("| input | stage | pointsurf s | peer s | ratio | points out (pointsurf / peer) | quality |")
print("|---|---|---|---|---|---|---|")
for c in cases:
    p, o = med(c, "pointsurf", "grid"), med(c, "open3d", "grid")
    if p and o:
        print(f"| {c} | grid vs Open3D voxel_down_sample | {p:.3f} | {o:.3f} | {p / o:.2f} | "
              f"{med(c, 'pointsurf', 'grid', 'output_points')} / {med(c, 'open3d', 'grid', 'output_points')} | |")
    q = med(c, "pointsurf", "pipeline")
    if q:
        print(f"| {c} | SOR + regional 10 % (one kd-tree) | {q:.3f} | | | {med(c, 'pointsurf', 'pipeline', 'output_points')} | target 0.3 s |")
    p, g = med(c, "pointsurf", "regional"), med(c, "cgal", "hierarchy")
    if p and g:
        qual = lambda tool, stage: (med(c, tool, stage, "chamfer_in_spacings"), med(c, tool, stage, "hausdorff_in_spacings"))
        pc, ph = qual("pointsurf", "regional")
        gc, gh = qual("cgal", "hierarchy-quality")
        print(f"| {c} | regional vs CGAL hierarchy_simplify_point_set | {p:.3f} | {g:.3f} | {p / g:.2f} | "
              f"{med(c, 'pointsurf', 'regional', 'output_points')} / {med(c, 'cgal', 'hierarchy', 'output_points')} | "
              f"Chamfer / Hausdorff in spacings: {pc:.2f} / {ph:.1f} vs {gc:.2f} / {gh:.1f} |")
PYEOF
