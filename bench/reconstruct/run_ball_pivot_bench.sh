#!/usr/bin/env bash
# Ball pivoting: pointsurf against Open3D 0.16 in the same run, on the same clouds, normals and radii.
#   bench/reconstruct/run_ball_pivot_bench.sh [SIZES] [REPEATS]   (default: 100000 3)
# Clouds: area-uniform samples of CGAL's armadillo.off (libcgal-demo) with the true face normals,
# clean and with Gaussian noise of 0.2 mean spacings (normals kept). Radii: {1.5, 3, 6} x the
# mean spacing of the clean cloud, given to both tools. Each run is its own process; the table
# shows medians of REPEATS runs (Open3D runs once at 1M points: it takes minutes), the time and
# memory ratio pointsurf / Open3D (below 1: pointsurf is faster / smaller), and the topology and
# Chamfer / Hausdorff distances to the true mesh (bench/reconstruct/mesh_metrics_runner). Raw
# results: bench/results/reconstruct_ball_pivot.csv (appended, with commit, date and machine).
# Needs: BUILD_DIR with ball_pivot_runner, mesh_metrics_runner and pointsurf_bench built.
set -euo pipefail
WORK_NAME=ball_pivot
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
SIZES="${1:-100000}"
REPEATS="${2:-3}"
O3D_LIMIT="${O3D_LIMIT:-1200}"
RUNNER="$BUILD_DIR/bench/ball_pivot_runner"


RESULTS="$WORK/results.jsonl"
: > "$RESULTS"
for n in $SIZES; do
  clean=$(sample_cloud "$n")
  spacing=$("$RUNNER" spacing "$clean")
  radii=$("$PY" -c "s=$spacing; print(','.join(repr(f*s) for f in (1.5, 3.0, 6.0)))")
  noisy="$WORK/${MESH}_${n}_noisy.ply"
  [ -f "$noisy" ] || "$RUNNER" noisify "$clean" "$("$PY" -c "print(0.2*$spacing)")" "$noisy"
  for kind in clean noisy; do
    cloud=$clean; [ "$kind" = noisy ] && cloud=$noisy
    for tool in pointsurf open3d; do
      runs=$REPEATS
      [ "$tool" = open3d ] && [ "$n" -ge 1000000 ] && runs=1
      mesh="$WORK/${tool}_${kind}_${n}.ply"
      for ((r = 0; r < runs; r++)); do
        echo "[$n $kind] $tool run $((r + 1))/$runs" >&2
        if [ "$tool" = pointsurf ]; then
          line=$("$RUNNER" run "$cloud" "$radii" "$mesh")
        else
          line=$(timeout "$O3D_LIMIT" "$PY" "$ROOT/bench/reconstruct/ball_pivot_open3d.py" "$cloud" "$radii" "$mesh") ||
            line="{\"tool\": \"open3d\", \"points\": $n, \"failed\": \"timeout ${O3D_LIMIT}s or error\"}"
        fi
        echo "$line" | "$PY" -c "import json,sys; d=json.loads(sys.stdin.read()); d['kind']='$kind'; d['run']=$r; print(json.dumps(d))" >> "$RESULTS"
      done
      if [ -f "$mesh" ]; then
        "$METRICS" "$mesh" "$OUT/$MESH.off" | "$PY" -c "import json,sys; d={'metrics': json.loads(sys.stdin.read())}; d.update(tool='$tool', points=$n, kind='$kind'); print(json.dumps(d))" >> "$RESULTS"
      fi
    done
  done
done

COMMIT=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
git -C "$ROOT" diff --quiet HEAD -- src include 2>/dev/null || COMMIT="$COMMIT+dirty"
PYTHONPATH="$ROOT/bench/reconstruct" "$PY" - "$RESULTS" "$MESH" "$ROOT/bench/results/reconstruct_ball_pivot.csv" "$COMMIT" <<'PYEOF' | tee "$OUT/ball_pivot.md"
import sys
from tables import find, load, median, metrics, ratio, results_csv
from tables import fmt as f
rows = load(sys.argv[1])
mesh = sys.argv[2]
csv_path, commit = sys.argv[3], sys.argv[4]
out, date, machine = results_csv(csv_path, ["commit", "date", "machine", "mesh", "points", "cloud", "tool", "runs", "seconds_median", "seconds_min", "seconds_max",
                  "pointsurf_time_ratio", "peak_rss_mb_median", "triangles", "holes", "boundary_edges", "non_manifold_edges",
                  "non_manifold_vertices", "components", "chamfer", "hausdorff"])
med = lambda tool, kind, n, key: median(rows, key, tool=tool, kind=kind, points=n)
metric = lambda tool, kind, n: metrics(rows, tool=tool, kind=kind, points=n)
print(f"Ball pivoting on area-uniform samples of CGAL's {mesh}.off (seed 1) with true normals; noisy: Gaussian")
print("noise of 0.2 mean spacings. Radii {1.5, 3, 6} x mean spacing for both tools. Medians; ratio = pointsurf / Open3D.")
print("Timing taken on a shared 2-core machine under load (other engineers compiling).\n")
print("| points | cloud | tool | seconds | time ratio | peak MB | memory ratio | triangles | holes | boundary edges | non-manifold edges | non-manifold vertices | components | Chamfer | Hausdorff |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for n in sorted({r["points"] for r in rows}):
    for kind in ["clean", "noisy"]:
        ps, os_ = med("pointsurf", kind, n, "seconds"), med("open3d", kind, n, "seconds")
        pm, om = med("pointsurf", kind, n, "peak_rss_mb"), med("open3d", kind, n, "peak_rss_mb")
        for tool, sec, mem in [("pointsurf", ps, pm), ("open3d", os_, om)]:
            m = metric(tool, kind, n)
            failed = sec is None and any(r.get("failed") for r in rows if r["tool"] == tool and r["kind"] == kind and r["points"] == n)
            print(f"| {n} | {kind} | {tool} | {'timeout' if failed else f(sec)} | {ratio(ps, os_) if tool == 'pointsurf' else ''} | "
                  f"{f(mem, 0)} | {ratio(pm, om) if tool == 'pointsurf' else ''} | {f(find(m, 'triangles'))} | {f(find(m, 'boundary_loops'))} | "
                  f"{f(find(m, 'boundary_edges'))} | {f(find(m, 'non_manifold_edges'))} | {f(find(m, 'non_manifold_vertices'))} | "
                  f"{f(find(m, 'components'))} | {f(find(m, 'chamfer'), 5)} | {f(find(m, 'hausdorff'), 5)} |")
            secs = [r["seconds"] for r in rows if r["tool"] == tool and r["kind"] == kind and r["points"] == n and "seconds" in r]
            out.writerow([commit, date, machine, mesh, n, kind, tool, len(secs), sec, min(secs) if secs else None,
                          max(secs) if secs else None, (ps / os_) if tool == "pointsurf" and ps and os_ else None, mem,
                          find(m, "triangles"), find(m, "boundary_loops"), find(m, "boundary_edges"), find(m, "non_manifold_edges"),
                          find(m, "non_manifold_vertices"), find(m, "components"), find(m, "chamfer"), find(m, "hausdorff")])
PYEOF
echo "results: $OUT/ball_pivot.md, bench/results/reconstruct_ball_pivot.csv" >&2
