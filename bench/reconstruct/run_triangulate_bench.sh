#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Region-growing triangulation (reconstruct_region_growing, defaults) against Open3D 0.16's ball
# pivoting in the same run, on the same clouds and normals.
#   bench/reconstruct/run_triangulate_bench.sh [SIZES] [REPEATS]   (default: "100000" 3)
# Clouds: area-uniform samples of CGAL's MESH.off (libcgal-demo; default armadillo, seed 1) with
# the true face normals. PCL's GreedyProjectionTriangulation, the closest peer, has no command
# line in pcl-tools, so Open3D's ball pivoting (radii {1.5, 3, 6} x pointsurf's mean spacing,
# through bench/reconstruct/ball_pivot_open3d.py) stands in for it. Each run is its own process;
# the table shows medians of REPEATS runs of time (reconstruction only, reading excluded) and
# peak memory (getrusage, whole process), the ratio pointsurf / Open3D (below 1: pointsurf is
# faster / smaller), pointsurf's stage times, and the topology and Chamfer / Hausdorff distances
# to the true mesh (bench/reconstruct/mesh_metrics_runner), in cloud units and in mean spacings.
# Needs: BUILD_DIR with triangulate_runner, mesh_metrics_runner and pointsurf_bench built.
set -euo pipefail
WORK_NAME=triangulate
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
SIZES="${1:-100000}"
REPEATS="${2:-3}"
RUNNER="$BUILD_DIR/bench/triangulate_runner"


RESULTS="$WORK/results.jsonl"
: > "$RESULTS"
for n in $SIZES; do
  cloud=$(sample_cloud "$n")
  radii=""
  for tool in pointsurf open3d; do
    mesh="$WORK/${tool}_${n}.ply"
    for ((r = 0; r < REPEATS; r++)); do
      echo "[$n] $tool run $((r + 1))/$REPEATS" >&2
      if [ "$tool" = pointsurf ]; then
        line=$("$RUNNER" run "$cloud" "$mesh")
        radii=$(echo "$line" | "$PY" -c "import json,sys; s=json.loads(sys.stdin.read())['mean_spacing']; print(','.join(str(f*s) for f in (1.5, 3, 6)))")
      else
        line=$("$PY" "$ROOT/bench/reconstruct/ball_pivot_open3d.py" "$cloud" "$radii" "$mesh")
      fi
      echo "$line" | "$PY" -c "import json,sys; d=json.loads(sys.stdin.read()); d['run']=$r; d.pop('loops', None); print(json.dumps(d))" >> "$RESULTS"
    done
    "$METRICS" "$mesh" "$OUT/$MESH.off" | "$PY" -c "import json,sys; d={'metrics': json.loads(sys.stdin.read())}; d.update(tool='$tool', points=$n); print(json.dumps(d))" >> "$RESULTS"
  done
done

"$PY" - "$RESULTS" "$MESH" <<'PYEOF' | tee "$OUT/triangulate.md"
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
mesh = sys.argv[2]
def med(tool, n, key, sub=None):
    v = [(r[key][sub] if sub else r[key]) for r in rows if r["tool"] == tool and r["points"] == n and key in r]
    return statistics.median(v) if v else None
def metric(tool, n):
    for r in rows:
        if r["tool"] == tool and r["points"] == n and "metrics" in r:
            return r["metrics"]
    return {}
def find(d, *names):
    for name in names:
        if name in d: return d[name]
        for v in d.values():
            if isinstance(v, dict) and name in v: return v[name]
    return None
f = lambda v, d=3: "-" if v is None else (f"{v:.{d}f}" if isinstance(v, float) else str(v))
ratio = lambda a, b: "-" if a is None or b is None or b == 0 else f"{a/b:.3f}"
print(f"Region growing (defaults) vs Open3D 0.16 ball pivoting (radii 1.5, 3, 6 mean spacings) on area-uniform samples of")
print(f"CGAL's {mesh}.off (seed 1, true normals). Medians; ratio = pointsurf / Open3D. Chamfer and Hausdorff to the true mesh")
print("in cloud units and (in brackets) in mean spacings. Timing taken on a shared 2-core machine under load.\n")
print("| points | tool | seconds | time ratio | peak MB | memory ratio | triangles | unused points | boundary edges | holes | non-manifold edges | non-manifold vertices | inconsistent edges | components | Chamfer | Hausdorff |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for n in sorted({r["points"] for r in rows}):
    ps, os_ = med("pointsurf", n, "seconds"), med("open3d", n, "seconds")
    pm, om = med("pointsurf", n, "peak_rss_mb"), med("open3d", n, "peak_rss_mb")
    spacing = med("pointsurf", n, "mean_spacing")
    for tool, sec, mem in [("pointsurf", ps, pm), ("open3d", os_, om)]:
        m = metric(tool, n)
        ch, hd = find(m, "chamfer"), find(m, "hausdorff")
        sp = lambda v: "" if v is None or not spacing else f" ({v/spacing:.2f})"
        holes = find(m, "boundary_loops", "holes")
        if isinstance(holes, list): holes = len(holes)
        print(f"| {n} | {tool} | {f(sec)} | {ratio(ps, os_) if tool == 'pointsurf' else ''} | {f(mem, 0)} | "
              f"{ratio(pm, om) if tool == 'pointsurf' else ''} | {f(find(m, 'triangles'))} | {f(med(tool, n, 'unused_points'))} | "
              f"{f(find(m, 'boundary_edges'))} | {f(holes)} | {f(find(m, 'non_manifold_edges'))} | {f(find(m, 'non_manifold_vertices'))} | "
              f"{f(find(m, 'inconsistent_edges'))} | {f(find(m, 'components'))} | {f(ch, 5)}{sp(ch)} | {f(hd, 5)}{sp(hd)} |")
    stages = ["tree_and_spacing", "umbrellas", "merge_candidates", "grow", "close_holes"]
    print(f"\npointsurf stages at {n} points (median seconds): " +
          ", ".join(f"{s} {f(med('pointsurf', n, 'stage_seconds', s))}" for s in stages))
PYEOF
echo "results: $OUT/triangulate.md" >&2
