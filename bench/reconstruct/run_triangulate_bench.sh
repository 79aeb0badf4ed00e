#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Region-growing triangulation (reconstruct_region_growing, defaults) against PCL 1.13's
# GreedyProjectionTriangulation (pcl_gp3_surface from pcl-tools, through
# bench/reconstruct/gp3_pcl.py: radius 6 x pointsurf's mean spacing, mu 2.5) and Open3D 0.16's
# ball pivoting (radii {1.5, 3, 6} x the mean spacing, bench/reconstruct/ball_pivot_open3d.py) in
# the same run, on the same clouds and normals. Raw results: bench/results/reconstruct_region_growing.csv
# (appended, with commit, date and machine).
#   bench/reconstruct/run_triangulate_bench.sh [SIZES] [REPEATS]   (default: "100000" 3)
#   PEERS="pcl_gp3 open3d" (default) chooses the peers; PEER_REPEATS (default REPEATS) their runs.
# Clouds: area-uniform samples of CGAL's MESH.off (libcgal-demo; default armadillo, seed 1) with
# the true face normals. Each run is its own process; the table shows medians of REPEATS runs of
# time (reconstruction only, reading excluded; for PCL the triangulation time the tool reports)
# and peak memory (getrusage, whole process), the ratio pointsurf / peer (below 1: pointsurf is
# faster / smaller), pointsurf's stage times, and the topology and Chamfer / Hausdorff distances
# to the true mesh (bench/reconstruct/mesh_metrics_runner), in cloud units and in mean spacings.
# Needs: BUILD_DIR with triangulate_runner, mesh_metrics_runner and pointsurf_bench built;
# pcl-tools and python3-open3d for the peers.
set -euo pipefail
WORK_NAME=triangulate
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
SIZES="${1:-100000}"
REPEATS="${2:-3}"
PEERS="${PEERS:-pcl_gp3 open3d}"
PEER_REPEATS="${PEER_REPEATS:-$REPEATS}"
RUNNER="$BUILD_DIR/bench/triangulate_runner"


RESULTS="$WORK/results.jsonl"
: > "$RESULTS"
for n in $SIZES; do
  cloud=$(sample_cloud "$n")
  radii=""
  gp3_radius=""
  for tool in pointsurf $PEERS; do
    mesh="$WORK/${tool}_${n}.ply"
    runs=$REPEATS
    [ "$tool" != pointsurf ] && runs=$PEER_REPEATS
    for ((r = 0; r < runs; r++)); do
      echo "[$n] $tool run $((r + 1))/$runs" >&2
      if [ "$tool" = pointsurf ]; then
        line=$("$RUNNER" run "$cloud" "$mesh")
        radii=$(echo "$line" | "$PY" -c "import json,sys; s=json.loads(sys.stdin.read())['mean_spacing']; print(','.join(str(f*s) for f in (1.5, 3, 6)))")
        gp3_radius=${radii##*,}
      elif [ "$tool" = pcl_gp3 ]; then
        line=$("$PY" "$ROOT/bench/reconstruct/gp3_pcl.py" "$cloud" "$gp3_radius" 2.5 "$mesh")
      else
        line=$("$PY" "$ROOT/bench/reconstruct/ball_pivot_open3d.py" "$cloud" "$radii" "$mesh")
      fi
      line=$(echo "$line" | "$PY" -c "import json,sys; d=json.loads(sys.stdin.read()); d['tool']='$tool'; d['points']=$n; print(json.dumps(d))")
      echo "$line" | "$PY" -c "import json,sys; d=json.loads(sys.stdin.read()); d['run']=$r; d.pop('loops', None); print(json.dumps(d))" >> "$RESULTS"
    done
    "$METRICS" "$mesh" "$OUT/$MESH.off" | "$PY" -c "import json,sys; d={'metrics': json.loads(sys.stdin.read())}; d.update(tool='$tool', points=$n); print(json.dumps(d))" >> "$RESULTS"
  done
done

COMMIT=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
git -C "$ROOT" diff --quiet HEAD -- src include 2>/dev/null || COMMIT="$COMMIT+dirty"
PYTHONPATH="$ROOT/bench/reconstruct" "$PY" - "$RESULTS" "$MESH" "$ROOT/bench/results/reconstruct_region_growing.csv" "$COMMIT" <<'PYEOF' | tee "$OUT/triangulate.md"
import sys
from tables import find, load, median, metrics, ratio, results_csv
from tables import fmt as f
rows = load(sys.argv[1])
mesh = sys.argv[2]
csv_path, commit = sys.argv[3], sys.argv[4]
med = lambda tool, n, key, sub=None: median(rows, key, sub, tool=tool, points=n)
metric = lambda tool, n: metrics(rows, tool=tool, points=n)
tools = ["pointsurf"] + [t for t in ("pcl_gp3", "open3d") if any(r["tool"] == t for r in rows)]
print(f"Region growing (defaults) vs PCL GP3 (pcl_gp3_surface, radius 6 mean spacings, mu 2.5) and Open3D 0.16 ball")
print(f"pivoting (radii 1.5, 3, 6 mean spacings) on area-uniform samples of CGAL's {mesh}.off (seed 1, true normals).")
print("Medians; ratio = pointsurf / peer. Chamfer and Hausdorff to the true mesh in cloud units and (in brackets) in mean")
print("spacings. Timing taken on a shared 2-core machine under load.\n")
print("| points | tool | runs | seconds | pointsurf / this | peak MB | triangles | unused points | boundary edges | holes | non-manifold edges | non-manifold vertices | inconsistent edges | components | Chamfer | Hausdorff |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
stages = ["tree_and_spacing", "umbrellas", "merge_candidates", "grow", "close_holes"]
out, date, machine = results_csv(csv_path, ["commit", "date", "machine", "mesh", "points", "tool", "runs", "seconds_median", "seconds_min", "seconds_max",
                  "pointsurf_time_ratio", "peak_rss_mb_median", "triangles", "boundary_edges", "holes", "non_manifold_edges",
                  "non_manifold_vertices", "inconsistent_edges", "components", "chamfer", "hausdorff", "mean_spacing"] +
                 [f"stage_{s}_median" for s in stages])
for n in sorted({r["points"] for r in rows}):
    ps = med("pointsurf", n, "seconds")
    spacing = med("pointsurf", n, "mean_spacing")
    for tool in tools:
        secs = [r["seconds"] for r in rows if r["tool"] == tool and r["points"] == n and "seconds" in r]
        sec, mem = med(tool, n, "seconds"), med(tool, n, "peak_rss_mb")
        m = metric(tool, n)
        ch, hd = find(m, "chamfer"), find(m, "hausdorff")
        sp = lambda v: "" if v is None or not spacing else f" ({v/spacing:.2f})"
        holes = find(m, "boundary_loops", "holes")
        if isinstance(holes, list): holes = len(holes)
        r_ = ratio(ps, sec) if tool != "pointsurf" else ""
        print(f"| {n} | {tool} | {len(secs)} | {f(sec)} | {r_} | {f(mem, 0)} | {f(find(m, 'triangles'))} | "
              f"{f(med(tool, n, 'unused_points'))} | {f(find(m, 'boundary_edges'))} | {f(holes)} | {f(find(m, 'non_manifold_edges'))} | "
              f"{f(find(m, 'non_manifold_vertices'))} | {f(find(m, 'inconsistent_edges'))} | {f(find(m, 'components'))} | "
              f"{f(ch, 5)}{sp(ch)} | {f(hd, 5)}{sp(hd)} |")
        stage_meds = [med(tool, n, "stage_seconds", s) if tool == "pointsurf" else None for s in stages]
        out.writerow([commit, date, machine, mesh, n, tool, len(secs), sec, min(secs) if secs else None, max(secs) if secs else None,
                      (ps / sec) if tool != "pointsurf" and ps and sec else None, mem, find(m, "triangles"),
                      find(m, "boundary_edges"), holes, find(m, "non_manifold_edges"), find(m, "non_manifold_vertices"),
                      find(m, "inconsistent_edges"), find(m, "components"), ch, hd, spacing] + stage_meds)
    print(f"\npointsurf stages at {n} points (median seconds): " +
          ", ".join(f"{s} {f(med('pointsurf', n, 'stage_seconds', s))}" for s in stages))
PYEOF
echo "results: $OUT/triangulate.md, bench/results/reconstruct_region_growing.csv" >&2
