#!/usr/bin/env bash
# Crust (cocone form) against CGAL 5.5's advancing front surface reconstruction, in the same run
# on the same clouds.
#   bench/reconstruct/run_crust_bench.sh [SIZES] [REPEATS]   (default: "100000" 3)
# Clouds: area-uniform samples of CGAL's MESH.off (libcgal-demo; default armadillo, seed 1);
# normals are dropped, so that pointsurf orients the mesh by its pole vectors. Each run is its own
# process; the table shows medians of REPEATS runs of time (reconstruction only, reading
# excluded) and peak memory (getrusage, whole process), the ratio pointsurf / CGAL (below 1:
# pointsurf is faster / smaller), and the topology and Chamfer / Hausdorff distances to the true
# mesh (bench/reconstruct/mesh_metrics_runner), in cloud units and in mean spacings.
# Needs: BUILD_DIR with crust_runner, mesh_metrics_runner and pointsurf_bench built; g++ and
# libcgal-dev (the CGAL peer bench/reconstruct/crust_cgal_aft.cpp is compiled here).
set -euo pipefail
WORK_NAME=crust
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
SIZES="${1:-100000}"
REPEATS="${2:-3}"
RUNNER="$BUILD_DIR/bench/crust_runner"
AFT="$WORK/crust_cgal_aft"

if [ ! -x "$AFT" ] || [ "$ROOT/bench/reconstruct/crust_cgal_aft.cpp" -nt "$AFT" ]; then
  echo "compiling the CGAL advancing-front peer" >&2
  g++ -O2 -DNDEBUG -std=c++17 -I/usr/include/eigen3 "$ROOT/bench/reconstruct/crust_cgal_aft.cpp" -o "$AFT" -lgmp -lmpfr
fi

RESULTS="$WORK/results.jsonl"
: > "$RESULTS"
for n in $SIZES; do
  cloud=$(sample_cloud "$n")
  xyz="$WORK/${MESH}_${n}.xyz"
  [ -f "$xyz" ] || "$RUNNER" xyz "$cloud" "$xyz"
  for tool in pointsurf cgal_aft; do
    mesh="$WORK/${tool}_${n}.ply"
    [ "$tool" = cgal_aft ] && mesh="$WORK/${tool}_${n}.off"
    for ((r = 0; r < REPEATS; r++)); do
      echo "[$n] $tool run $((r + 1))/$REPEATS" >&2
      if [ "$tool" = pointsurf ]; then
        line=$("$RUNNER" run "$cloud" "$mesh" drop_normals)
      else
        line=$("$AFT" "$xyz" "$mesh")
      fi
      echo "$line" | "$PY" -c "import json,sys; d=json.loads(sys.stdin.read()); d['run']=$r; print(json.dumps(d))" >> "$RESULTS"
    done
    "$METRICS" "$mesh" "$OUT/$MESH.off" | "$PY" -c "import json,sys; d={'metrics': json.loads(sys.stdin.read())}; d.update(tool='$tool', points=$n); print(json.dumps(d))" >> "$RESULTS"
  done
done

"$PY" - "$RESULTS" "$MESH" <<'PYEOF' | tee "$OUT/crust.md"
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
mesh = sys.argv[2]
def med(tool, n, key):
    v = [r[key] for r in rows if r["tool"] == tool and r["points"] == n and key in r]
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
print(f"Crust (cocone form, defaults) vs CGAL 5.5 advancing front (defaults) on area-uniform samples of CGAL's {mesh}.off")
print("(seed 1, normals dropped). Medians; ratio = pointsurf / CGAL. Chamfer and Hausdorff to the true mesh in cloud units")
print("and (in brackets) in mean spacings. Timing taken on a shared 2-core machine under load (other engineers compiling).\n")
print("| points | tool | seconds | time ratio | peak MB | memory ratio | triangles | unused points | boundary edges | non-manifold edges | non-manifold vertices | inconsistent edges | components | Chamfer | Hausdorff |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for n in sorted({r["points"] for r in rows}):
    ps, cs = med("pointsurf", n, "seconds"), med("cgal_aft", n, "seconds")
    pm, cm = med("pointsurf", n, "peak_rss_mb"), med("cgal_aft", n, "peak_rss_mb")
    spacing = med("pointsurf", n, "mean_spacing")
    for tool, sec, mem in [("pointsurf", ps, pm), ("cgal_aft", cs, cm)]:
        m = metric(tool, n)
        ch, hd = find(m, "chamfer"), find(m, "hausdorff")
        sp = lambda v: "" if v is None or not spacing else f" ({v/spacing:.2f})"
        print(f"| {n} | {tool} | {f(sec)} | {ratio(ps, cs) if tool == 'pointsurf' else ''} | {f(mem, 0)} | "
              f"{ratio(pm, cm) if tool == 'pointsurf' else ''} | {f(find(m, 'triangles'))} | {f(med(tool, n, 'unused_points'))} | "
              f"{f(find(m, 'boundary_edges'))} | {f(find(m, 'non_manifold_edges'))} | {f(find(m, 'non_manifold_vertices'))} | "
              f"{f(find(m, 'inconsistent_edges'))} | {f(find(m, 'components'))} | {f(ch, 5)}{sp(ch)} | {f(hd, 5)}{sp(hd)} |")
PYEOF
echo "results: $OUT/crust.md" >&2
