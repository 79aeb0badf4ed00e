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
# Then (HOLES=1, the default) the hole counts of every pointsurf method through the CLI, with hole
# filling on (defaults) and off (--max-hole-perimeter-in-spacings 0), next to Open3D 0.16's ball
# pivoting (which fills none; same cloud, normals and radii {1.5, 3, 6} x mean spacing as
# pointsurf's ball pivoting) and CGAL's advancing front, on the sample with its true normals
# (cocone and Crust use them to orient only). One run each, no timing. Raw results:
# bench/results/reconstruct_holes.csv.
# Needs: BUILD_DIR with pointsurf, cocone_runner, mesh_metrics_runner and pointsurf_bench built;
# g++ and libcgal-dev (the CGAL peer bench/reconstruct/cgal_aft.cpp is compiled here).
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

[ "${HOLES:-1}" = 1 ] || exit 0
HOLE_RESULTS="$WORK/holes.jsonl"
: > "$HOLE_RESULTS"
for n in $SIZES; do
  cloud=$(sample_cloud "$n")
  xyz="$WORK/${MESH}_${n}.xyz"
  spacing=$("$PY" -c "import open3d as o3d, numpy as np; c=o3d.io.read_point_cloud('$cloud'); print(np.mean(c.compute_nearest_neighbor_distance()))")
  radii=$("$PY" -c "s=$spacing; print(','.join(repr(f*s) for f in (1.5, 3.0, 6.0)))")
  for tool in triangulate ball-pivot cocone crust open3d_ball_pivot cgal_aft; do
    for fill in on off; do
      case $tool in open3d_ball_pivot|cgal_aft) [ $fill = off ] || continue ;; esac
      mesh="$WORK/holes_${tool}_${fill}_${n}.ply"
      echo "[$n] holes: $tool, filling $fill" >&2
      case $tool in
        open3d_ball_pivot) "$PY" "$ROOT/bench/reconstruct/ball_pivot_open3d.py" "$cloud" "$radii" "$mesh" > /dev/null ;;
        cgal_aft) mesh="${mesh%.ply}.off"; "$AFT" "$xyz" "$mesh" > /dev/null ;;
        *)
          extra=(); [ $fill = off ] && extra=(--max-hole-perimeter-in-spacings 0)
          [ $tool = ball-pivot ] && extra+=(--radii "$radii")
          "$BUILD_DIR/pointsurf" reconstruct "$cloud" "$mesh" --method "$tool" "${extra[@]}" > /dev/null 2>&1 ;;
      esac
      "$METRICS" "$mesh" "$OUT/$MESH.off" | "$PY" -c "import json,sys; d={'metrics': json.loads(sys.stdin.read())}; d.update(tool='$tool', fill='$fill', points=$n, spacing=$spacing); print(json.dumps(d))" >> "$HOLE_RESULTS"
    done
  done
done
PYTHONPATH="$ROOT/bench/reconstruct" "$PY" - "$HOLE_RESULTS" "$MESH" "$ROOT/bench/results/reconstruct_holes.csv" "$COMMIT" <<'PYEOF' | tee "$OUT/holes_$MESH.md"
import sys
from tables import find, load, results_csv
from tables import fmt as f
rows = load(sys.argv[1])
mesh, csv_path, commit = sys.argv[2], sys.argv[3], sys.argv[4]
print(f"Holes with hole filling on (defaults) and off (--max-hole-perimeter-in-spacings 0) on an area-uniform sample of CGAL's {mesh}.off")
print("(seed 1, true normals); Open3D's ball pivoting and CGAL's advancing front fill none. Hausdorff to the true mesh in mean spacings.\n")
print("| points | tool | filling | triangles | holes (boundary loops) | boundary edges | boundary edges per face | largest hole (spacings round) | non-manifold edges | non-manifold vertices | components | Hausdorff |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|")
out, date, machine = results_csv(csv_path, ["commit", "date", "machine", "mesh", "points", "tool", "filling", "triangles", "holes", "boundary_edges",
                                            "boundary_edges_per_face", "largest_hole_length", "non_manifold_edges", "non_manifold_vertices",
                                            "components", "hausdorff", "mean_spacing"])
for r in rows:
    m, sp = r["metrics"], r["spacing"]
    tris, be, loops = find(m, "triangles"), find(m, "boundary_edges"), find(m, "boundary_loops")
    largest, hd = find(m, "largest_boundary_length"), find(m, "hausdorff")
    per_face = be / tris if tris else None
    fill = r["fill"] if r["tool"] not in ("open3d_ball_pivot", "cgal_aft") else "none"
    print(f"| {r['points']} | {r['tool']} | {fill} | {f(tris)} | {f(loops)} | {f(be)} | {f(per_face, 5)} | "
          f"{f(largest / sp if largest is not None else None, 0)} | {f(find(m, 'non_manifold_edges'))} | "
          f"{f(find(m, 'non_manifold_vertices'))} | {f(find(m, 'components'))} | {f(hd / sp if hd is not None else None, 2)} |")
    out.writerow([commit, date, machine, mesh, r["points"], r["tool"], fill, tris, loops, be, per_face, largest,
                  find(m, "non_manifold_edges"), find(m, "non_manifold_vertices"), find(m, "components"), hd, sp])
PYEOF
echo "results: $OUT/holes_$MESH.md, bench/results/reconstruct_holes.csv" >&2
