#!/usr/bin/env bash
# Benchmarks pointsurf against Open3D in the same run on clouds sampled from a real mesh.
#   bench/run_bench.sh [SIZES] [REPEATS]      (default: "100000 1000000" 3)
# Run through `./pointsurf.sh bench`, which installs python3-open3d and libcgal-demo and builds
# bench/pointsurf_bench. Each stage runs in its own process (peak memory per stage, file
# reading included in memory, excluded from time except for "read"), the two tools
# interleaved; the table shows medians of REPEATS runs and the ratio pointsurf / Open3D (below
# 1: pointsurf is faster / smaller), on wall time and on CPU time (user + system, all threads:
# the fair figure when other processes load the machine). Open3D's memory is given raw and net
# of its interpreter + numpy + open3d baseline, measured in the same run. kNN runs in both
# query orders for both tools. Open3D's MST orientation is run once per size (it needs minutes
# at 1M points), under a time limit of O3D_ORIENT_LIMIT seconds (default 900).
# Raw rows (commit, date, machine, load) are appended to bench/results/normals_bench.csv.
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
for ((r = 0; r < REPEATS; r++)); do
  "$BUILD_DIR/bench/pointsurf_bench" baseline >> "$RESULTS"
  "$PY" "$ROOT/bench/open3d_bench.py" baseline >> "$RESULTS"
done
# Stage pairs: pointsurf's name, Open3D's name (the same query order for kNN).
pairs="${PAIRS:-read:read write:write knn:knn_spatial knn_input:knn normals:normals orient:orient}"
for n in $SIZES; do
  cloud="$OUT/${MESH}_${n}.ply"
  [ -f "$cloud" ] || "$BUILD_DIR/bench/pointsurf_bench" sample "$OUT/$MESH.off" "$n" "$cloud" 1
  for pair in $pairs; do
    ours="${pair%%:*}" theirs="${pair##*:}"
    for ((r = 0; r < REPEATS; r++)); do
      echo "[$n] $ours pointsurf run $((r + 1))/$REPEATS" >&2
      "$BUILD_DIR/bench/pointsurf_bench" "$ours" "$cloud" | sed "s/}\$/, \"load\": $(cut -d' ' -f1 /proc/loadavg)}/" >> "$RESULTS"
      if [ "$ours" = orient ] && [ "$r" -gt 0 ]; then continue; fi
      echo "[$n] $theirs open3d run $((r + 1))" >&2
      limit=600
      [ "$ours" = orient ] && limit="$O3D_ORIENT_LIMIT"
      if ! timeout "$limit" "$PY" "$ROOT/bench/open3d_bench.py" "$theirs" "$cloud" | sed "s/}\$/, \"load\": $(cut -d' ' -f1 /proc/loadavg)}/" >> "$RESULTS"; then
        echo "{\"tool\": \"open3d\", \"stage\": \"$theirs\", \"points\": $n, \"failed\": \"timeout ${limit}s or error\"}" >> "$RESULTS"
      fi
    done
  done
done

COMMIT="$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)"
MACHINE="$(nproc) cores, $(awk '/MemTotal/ {printf "%.0f GB", $2 / 1048576}' /proc/meminfo), $(uname -m)"
"$PY" - "$RESULTS" "$MESH" "$COMMIT" "$MACHINE" "$ROOT/bench/results/normals_bench.csv" "$pairs" <<'PYEOF' | tee "$OUT/results.md"
import csv, datetime, json, os, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
mesh, commit, machine, csv_path = sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5]
pairs = [p.split(":") for p in sys.argv[6].split()]
date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%MZ")
fields = ["commit", "date", "machine", "load", "tool", "stage", "points", "seconds", "cpu_seconds", "peak_rss_mb",
          "mean_angle_deg", "consistent_share", "outward_share", "failed"]
new = not os.path.exists(csv_path)
with open(csv_path, "a", newline="") as f:
    w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
    if new:
        w.writeheader()
    for r in rows:
        w.writerow({**r, "commit": commit, "date": date, "machine": machine})

def med(tool, stage, n, key):
    v = [r[key] for r in rows if r["tool"] == tool and r["stage"] == stage and r["points"] == n and key in r]
    return statistics.median(v) if v else None
base = {t: med(t, "baseline", 0, "peak_rss_mb") for t in ("pointsurf", "open3d")}
def quality(stage, tool, n):
    if stage == "normals":
        v = med(tool, stage, n, "mean_angle_deg"); return f"{v:.2f} deg" if v is not None else "-"
    if stage == "orient":
        c = med(tool, stage, n, "consistent_share"); o = med(tool, stage, n, "outward_share")
        return f"{100*c:.2f} % consistent, {100*o:.2f} % outward" if c is not None else "-"
    return ""
f = lambda v, d=3: "-" if v is None else f"{v:.{d}f}"
ratio = lambda a, b: "-" if a is None or b is None or b == 0 else f"{a/b:.3f}"
loads = [r["load"] for r in rows if "load" in r]
print(f"Cloud: area-uniform samples of CGAL's {mesh}.off (seed 1). Medians; ratio = pointsurf / Open3D. "
      f"Commit {commit}, {date}, {machine}, load average {min(loads):.1f}-{max(loads):.1f} during the runs. "
      f"Baselines (process that reads nothing): pointsurf {f(base['pointsurf'],1)} MB, Open3D {f(base['open3d'],1)} MB "
      f"(python, numpy, open3d); net = raw - baseline.\n")
print("| points | stage | pointsurf s | Open3D s | wall ratio | pointsurf CPU s | Open3D CPU s | CPU ratio | pointsurf MB | Open3D MB raw / net | memory ratio raw / net | pointsurf quality | Open3D quality |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
names = {"knn": "knn, spatial order", "knn_input": "knn, input order"}
for n in sorted({r["points"] for r in rows if r["points"]}):
    for ours, theirs in pairs:
        ps, os_ = med("pointsurf", ours, n, "seconds"), med("open3d", theirs, n, "seconds")
        pc, oc = med("pointsurf", ours, n, "cpu_seconds"), med("open3d", theirs, n, "cpu_seconds")
        pm, om = med("pointsurf", ours, n, "peak_rss_mb"), med("open3d", theirs, n, "peak_rss_mb")
        pn = None if pm is None else pm - (base["pointsurf"] or 0)
        on = None if om is None else om - (base["open3d"] or 0)
        failed = any(r.get("failed") for r in rows if r["tool"] == "open3d" and r["stage"] == theirs and r["points"] == n)
        o_txt = "timeout" if os_ is None and failed else f(os_)
        print(f"| {n} | {names.get(ours, ours)} | {f(ps)} | {o_txt} | {ratio(ps, os_)} | {f(pc)} | {f(oc)} | {ratio(pc, oc)} | "
              f"{f(pm,0)} | {f(om,0)} / {f(on,0)} | {ratio(pm, om)} / {ratio(pn, on)} | {quality(ours,'pointsurf',n)} | {quality(theirs,'open3d',n)} |")
PYEOF
echo "results: $OUT/results.md" >&2
