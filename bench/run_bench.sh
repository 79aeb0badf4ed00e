#!/usr/bin/env bash
# Benchmarks pointsurf against Open3D in the same run on clouds sampled from a real mesh.
#   bench/run_bench.sh [SIZES] [REPEATS]      (default: "100000 1000000" 3)
# Run through `./pointsurf.sh bench`, which installs python3-open3d and libcgal-demo and builds
# bench/pointsurf_bench. Each stage runs in its own process (peak memory per stage, file
# reading included in memory, excluded from time except for "read"); the table shows medians
# of REPEATS runs and the ratio pointsurf / Open3D (below 1: pointsurf is faster / smaller).
# Open3D's MST orientation is run once per size (it needs minutes at 1M points), under a
# time limit of O3D_ORIENT_LIMIT seconds (default 900).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
SIZES="${1:-100000 1000000}"
REPEATS="${2:-3}"
MESH="${MESH:-armadillo}"
O3D_ORIENT_LIMIT="${O3D_ORIENT_LIMIT:-900}"
OUT="$ROOT/bench/out"
PY=/usr/bin/python3
mkdir -p "$OUT"

ARCHIVE=/usr/share/doc/libcgal-demo/data.tar.gz
if [ ! -f "$OUT/$MESH.off" ]; then
  tar xzf "$ARCHIVE" -C "$OUT" "data/meshes/$MESH.off"
  mv "$OUT/data/meshes/$MESH.off" "$OUT/$MESH.off"
  rm -rf "$OUT/data"
fi

RESULTS="$OUT/results.jsonl"
: > "$RESULTS"
for n in $SIZES; do
  cloud="$OUT/${MESH}_${n}.ply"
  [ -f "$cloud" ] || "$BUILD_DIR/bench/pointsurf_bench" sample "$OUT/$MESH.off" "$n" "$cloud" 1
  for stage in read write knn normals orient; do
    for ((r = 0; r < REPEATS; r++)); do
      echo "[$n] $stage pointsurf run $((r + 1))/$REPEATS" >&2
      "$BUILD_DIR/bench/pointsurf_bench" "$stage" "$cloud" >> "$RESULTS"
      if [ "$stage" = orient ] && [ "$r" -gt 0 ]; then continue; fi
      echo "[$n] $stage open3d run $((r + 1))" >&2
      limit=600
      [ "$stage" = orient ] && limit="$O3D_ORIENT_LIMIT"
      if ! timeout "$limit" "$PY" "$ROOT/bench/open3d_bench.py" "$stage" "$cloud" >> "$RESULTS"; then
        echo "{\"tool\": \"open3d\", \"stage\": \"$stage\", \"points\": $n, \"failed\": \"timeout ${limit}s or error\"}" >> "$RESULTS"
      fi
    done
  done
done

"$PY" - "$RESULTS" "$MESH" <<'PYEOF' | tee "$OUT/results.md"
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
mesh = sys.argv[2]
def med(tool, stage, n, key):
    v = [r[key] for r in rows if r["tool"] == tool and r["stage"] == stage and r["points"] == n and key in r]
    return statistics.median(v) if v else None
def quality(stage, tool, n):
    if stage == "normals":
        v = med(tool, stage, n, "mean_angle_deg"); return f"{v:.2f} deg" if v is not None else "-"
    if stage == "orient":
        c = med(tool, stage, n, "consistent_share"); o = med(tool, stage, n, "outward_share")
        return f"{100*c:.2f} % consistent, {100*o:.2f} % outward" if c is not None else "-"
    return ""
print(f"Cloud: area-uniform samples of CGAL's {mesh}.off (seed 1). Medians; ratio = pointsurf / Open3D.\n")
print("| points | stage | pointsurf s | Open3D s | time ratio | pointsurf MB | Open3D MB | memory ratio | pointsurf quality | Open3D quality |")
print("|---|---|---|---|---|---|---|---|---|---|")
for n in sorted({r["points"] for r in rows}):
    for stage in ["read", "write", "knn", "normals", "orient"]:
        ps, os_ = med("pointsurf", stage, n, "seconds"), med("open3d", stage, n, "seconds")
        pm, om = med("pointsurf", stage, n, "peak_rss_mb"), med("open3d", stage, n, "peak_rss_mb")
        f = lambda v, d=3: "-" if v is None else f"{v:.{d}f}"
        ratio = lambda a, b: "-" if a is None or b is None or b == 0 else f"{a/b:.3f}"
        if os_ is None and any(r.get("failed") for r in rows if r["tool"] == "open3d" and r["stage"] == stage and r["points"] == n):
            o_txt = "timeout"
        else:
            o_txt = f(os_)
        print(f"| {n} | {stage} | {f(ps)} | {o_txt} | {ratio(ps, os_)} | {f(pm,0)} | {f(om,0)} | {ratio(pm, om)} | {quality(stage,'pointsurf',n)} | {quality(stage,'open3d',n)} |")
PYEOF
echo "results: $OUT/results.md" >&2
