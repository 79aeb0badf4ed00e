#!/usr/bin/env bash
# The cocone and the two-pass Crust against CGAL 5.5's advancing front surface reconstruction, in
# the same run on the same clouds. Raw results: bench/results/reconstruct_delaunay.csv (appended,
# with commit and date).
#   bench/reconstruct/run_cocone_bench.sh [SIZES] [REPEATS]   (default: "100000" 3)
# Clouds: area-uniform samples of CGAL's MESH.off (libcgal-demo; default armadillo, seed 1);
# normals are dropped, so that pointsurf orients the mesh by its pole vectors. Each run is its own
# process; the table shows medians of REPEATS runs of time (reconstruction only, reading
# excluded) and peak memory (getrusage, whole process), the ratio pointsurf / CGAL (below 1:
# pointsurf is faster / smaller), and the topology and Chamfer / Hausdorff distances to the true
# mesh (bench/reconstruct/mesh_metrics_runner), in cloud units and in mean spacings.
# Needs: BUILD_DIR with cocone_runner, mesh_metrics_runner and pointsurf_bench built; g++ and
# libcgal-dev (the CGAL peer bench/reconstruct/cgal_aft.cpp is compiled here).
set -euo pipefail
WORK_NAME=cocone
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
SIZES="${1:-100000}"
REPEATS="${2:-3}"
RUNNER="$BUILD_DIR/bench/cocone_runner"
AFT="$WORK/cgal_aft"

if [ ! -x "$AFT" ] || [ "$ROOT/bench/reconstruct/cgal_aft.cpp" -nt "$AFT" ]; then
  echo "compiling the CGAL advancing-front peer" >&2
  g++ -O2 -DNDEBUG -std=c++17 -I/usr/include/eigen3 "$ROOT/bench/reconstruct/cgal_aft.cpp" -o "$AFT" -lgmp -lmpfr
fi

RESULTS="$WORK/results.jsonl"
: > "$RESULTS"
for n in $SIZES; do
  cloud=$(sample_cloud "$n")
  xyz="$WORK/${MESH}_${n}.xyz"
  [ -f "$xyz" ] || "$RUNNER" xyz "$cloud" "$xyz"
  for tool in pointsurf_cocone pointsurf_crust cgal_aft; do
    mesh="$WORK/${tool}_${n}.ply"
    [ "$tool" = cgal_aft ] && mesh="$WORK/${tool}_${n}.off"
    for ((r = 0; r < REPEATS; r++)); do
      echo "[$n] $tool run $((r + 1))/$REPEATS" >&2
      if [ "$tool" != cgal_aft ]; then
        line=$("$RUNNER" run "$cloud" "$mesh" drop_normals "${tool#pointsurf_}")
      else
        line=$("$AFT" "$xyz" "$mesh")
      fi
      echo "$line" | "$PY" -c "import json,sys; d=json.loads(sys.stdin.read()); d['run']=$r; print(json.dumps(d))" >> "$RESULTS"
    done
    "$METRICS" "$mesh" "$OUT/$MESH.off" | "$PY" -c "import json,sys; d={'metrics': json.loads(sys.stdin.read())}; d.update(tool='$tool', points=$n); print(json.dumps(d))" >> "$RESULTS"
  done
done

COMMIT=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
PYTHONPATH="$ROOT/bench/reconstruct" "$PY" - "$RESULTS" "$MESH" "$ROOT/bench/results/reconstruct_delaunay.csv" "$COMMIT" <<'PYEOF' | tee "$OUT/cocone.md"
import sys
from tables import find, load, median, metrics, ratio, results_csv
from tables import fmt as f
rows = load(sys.argv[1])
mesh = sys.argv[2]
csv_path, commit = sys.argv[3], sys.argv[4]
med = lambda tool, n, key: median(rows, key, tool=tool, points=n)
metric = lambda tool, n: metrics(rows, tool=tool, points=n)
print(f"Cocone and Crust (defaults) vs CGAL 5.5 advancing front (defaults) on area-uniform samples of CGAL's {mesh}.off")
print("(seed 1, normals dropped). Medians; ratio = pointsurf / CGAL. Chamfer and Hausdorff to the true mesh in cloud units")
print("and (in brackets) in mean spacings. Timing taken on a shared 2-core machine under load (other engineers compiling).\n")
print("| points | tool | seconds | time ratio | peak MB | memory ratio | triangles | unused points | boundary edges | non-manifold edges | non-manifold vertices | inconsistent edges | components | Chamfer | Hausdorff |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
out, date, machine = results_csv(csv_path, ["commit", "date", "machine", "mesh", "points", "tool", "seconds_median", "peak_rss_mb_median", "runs", "triangles",
                  "boundary_edges", "boundary_edges_per_face", "non_manifold_edges", "non_manifold_vertices", "components", "chamfer", "hausdorff",
                  "mean_spacing"])
for n in sorted({r["points"] for r in rows}):
    cs, cm = med("cgal_aft", n, "seconds"), med("cgal_aft", n, "peak_rss_mb")
    spacing = med("pointsurf_cocone", n, "mean_spacing")
    for tool in ["pointsurf_cocone", "pointsurf_crust", "cgal_aft"]:
        sec, mem = med(tool, n, "seconds"), med(tool, n, "peak_rss_mb")
        m = metric(tool, n)
        ch, hd = find(m, "chamfer"), find(m, "hausdorff")
        tris, be = find(m, "triangles"), find(m, "boundary_edges")
        sp = lambda v: "" if v is None or not spacing else f" ({v/spacing:.2f})"
        mine = tool != "cgal_aft"
        print(f"| {n} | {tool} | {f(sec)} | {ratio(sec, cs) if mine else ''} | {f(mem, 0)} | "
              f"{ratio(mem, cm) if mine else ''} | {f(tris)} | {f(med(tool, n, 'unused_points'))} | "
              f"{f(be)} | {f(find(m, 'non_manifold_edges'))} | {f(find(m, 'non_manifold_vertices'))} | "
              f"{f(find(m, 'inconsistent_edges'))} | {f(find(m, 'components'))} | {f(ch, 5)}{sp(ch)} | {f(hd, 5)}{sp(hd)} |")
        runs = len([r for r in rows if r["tool"] == tool and r["points"] == n and "seconds" in r])
        out.writerow([commit, date, machine, mesh, n, tool, sec, mem, runs, tris, be,
                      (be / tris) if tris and be is not None else None, find(m, "non_manifold_edges"),
                      find(m, "non_manifold_vertices"), find(m, "components"), ch, hd, spacing])
PYEOF
echo "results: $OUT/cocone.md, bench/results/reconstruct_delaunay.csv" >&2
