#!/bin/bash
# Segmentation benchmark on the 1M-point primitive scene (make_scene.py), interleaved runs,
# medians of REPEATS:
#   ransac:  pointsurf detect_primitives vs CGAL Shape_detection efficient RANSAC (same epsilon,
#            cluster epsilon, normal threshold, min points, probability)
#   planes:  pointsurf planes only (min points 100k: the two true planes) vs Open3D segment_plane
#            twice (1000 iterations)
#   cluster: pointsurf segment_euclidean vs Open3D cluster_dbscan (min_points 1), same radius
#   building: ransac on CGAL's demo building.ply (unseen; its segment_index as reference, planes
#            of >= 500 points scored), pointsurf's default parameters given to both
#   mixed:   ransac on make_mixed_scene.py (200k points, 18 primitives of random type, size and
#            orientation; unseen), pointsurf's defaults (1 and 3 mean spacings, N / 200) given to both
#   fandisk: ransac on CGAL's demo fandisk.off sampled with face normals (100k; unseen, no
#            reference: "completeness" is the fraction of points assigned), defaults given to both
# Writes bench/results/segment.csv (raw runs) and prints a Markdown table.
#   bench/segment/run_segment_bench.sh [BUILD_DIR] [REPEATS]
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${1:-$ROOT/build}
REPEATS=${2:-3}
PY=/usr/bin/python3
WORK=$(mktemp -d /tmp/pointsurf_segment_bench.XXXX)
CGAL_BIN="$WORK/cgal_efficient_ransac"
g++ -O2 -std=c++17 -DNDEBUG -I/usr/include/eigen3 "$ROOT/bench/segment/cgal_efficient_ransac.cpp" -o "$CGAL_BIN" -lgmp -lmpfr
RUNNER="$BUILD/bench/segment_runner"
$PY "$ROOT/bench/segment/make_scene.py" 1000000 0.005 "$WORK/scene.ply" "$WORK/scene.bin" > /dev/null
EPS=0.02 CLUSTER=0.05 NORMAL=25 MIN=2000 PROB=0.01
tar xzf /usr/share/doc/libcgal-demo/data.tar.gz -C "$WORK" data/points_3/building.ply
$PY "$ROOT/bench/segment/building_case.py" "$WORK/data/points_3/building.ply" "$WORK/building.ply" "$WORK/building.bin"
# pointsurf's defaults on building.ply: epsilon 1 mean spacing, cluster epsilon 3, min points N / 200.
B_EPS=0.1369529134601264 B_CLUSTER=0.4108587403803792 B_MIN=500
read -r M_N M_SPACING < <($PY "$ROOT/bench/segment/make_mixed_scene.py" 200000 0.005 7 "$WORK/mixed.ply" "$WORK/mixed.bin")
M_CLUSTER=$($PY -c "print(3 * $M_SPACING)") M_MIN=$((M_N / 200))
tar xzf /usr/share/doc/libcgal-demo/data.tar.gz -C "$WORK" data/meshes/fandisk.off
read -r F_N F_SPACING < <($PY "$ROOT/bench/segment/sample_mesh.py" "$WORK/data/meshes/fandisk.off" 100000 "$WORK/fandisk.ply" "$WORK/fandisk.bin")
F_CLUSTER=$($PY -c "print(3 * $F_SPACING)") F_MIN=$((F_N / 200))
assigned() {  # runner json, N: the fraction assigned as a score line
  $PY -c "import json, sys; j = json.loads(sys.argv[1]); print(json.dumps({'shares': [1 - j['unassigned'] / $2], 'recovered_95': 0}))" "$1"
}
CSV="$ROOT/bench/results/segment.csv"
COMMIT=$(git -C "$ROOT" rev-parse --short HEAD)
DATE=$(date -u +%Y-%m-%dT%H:%M:%SZ)
MACHINE="$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
[ -f "$CSV" ] || echo "commit,date,machine,load,task,tool,run,seconds,primitives,completeness,recovered_95" > "$CSV"
row() {  # task tool run json score_json
  local load; load=$(cut -d' ' -f1 /proc/loadavg)
  $PY - "$COMMIT" "$DATE" "$MACHINE" "$load" "$1" "$2" "$3" "$4" "$5" >> "$CSV" <<'PYEOF'
import json, sys
c, d, m, load, task, tool, run, line, score = sys.argv[1:]
j, s = json.loads(line), json.loads(score)
prims = j.get("primitives", j.get("segments"))
comp = sum(s["shares"]) / len(s["shares"])
print(f'{c},{d},"{m}",{load},{task},{tool},{run},{j["seconds"]},{prims},{comp:.4f},{s["recovered_95"]}')
PYEOF
}
for r in $(seq 1 "$REPEATS"); do
  echo "run $r/$REPEATS (load $(cut -d' ' -f1 /proc/loadavg))" >&2
  j=$("$RUNNER" ransac "$WORK/scene.ply" all $EPS $CLUSTER $NORMAL $MIN $PROB "$WORK/ps.labels")
  row ransac pointsurf "$r" "$j" "$($PY "$ROOT/bench/segment/score_labels.py" "$WORK/scene.ply" "$WORK/ps.labels")"
  j=$("$CGAL_BIN" "$WORK/scene.bin" $EPS $CLUSTER $NORMAL $MIN $PROB all "$WORK/cgal.labels")
  row ransac cgal "$r" "$j" "$($PY "$ROOT/bench/segment/score_labels.py" "$WORK/scene.ply" "$WORK/cgal.labels")"
  j=$("$RUNNER" ransac "$WORK/scene.ply" plane $EPS $CLUSTER $NORMAL 100000 $PROB "$WORK/psp.labels")
  row planes pointsurf "$r" "$j" "$($PY "$ROOT/bench/segment/score_labels.py" "$WORK/scene.ply" "$WORK/psp.labels" 0,1)"
  j=$($PY "$ROOT/bench/segment/open3d_segment.py" planes "$WORK/scene.ply" $EPS $MIN 1000 2 "$WORK/o3dp.labels")
  row planes open3d "$r" "$j" "$($PY "$ROOT/bench/segment/score_labels.py" "$WORK/scene.ply" "$WORK/o3dp.labels" 0,1)"
  j=$("$RUNNER" ransac "$WORK/building.ply" all $B_EPS $B_CLUSTER $NORMAL $B_MIN $PROB "$WORK/bps.labels")
  row building pointsurf "$r" "$j" "$($PY "$ROOT/bench/segment/score_labels.py" "$WORK/building.ply" "$WORK/bps.labels" big500)"
  j=$("$CGAL_BIN" "$WORK/building.bin" $B_EPS $B_CLUSTER $NORMAL $B_MIN $PROB all "$WORK/bcgal.labels")
  row building cgal "$r" "$j" "$($PY "$ROOT/bench/segment/score_labels.py" "$WORK/building.ply" "$WORK/bcgal.labels" big500)"
  j=$("$RUNNER" ransac "$WORK/mixed.ply" all $M_SPACING $M_CLUSTER $NORMAL $M_MIN $PROB "$WORK/mps.labels")
  row mixed pointsurf "$r" "$j" "$($PY "$ROOT/bench/segment/score_labels.py" "$WORK/mixed.ply" "$WORK/mps.labels")"
  j=$("$CGAL_BIN" "$WORK/mixed.bin" $M_SPACING $M_CLUSTER $NORMAL $M_MIN $PROB all "$WORK/mcgal.labels")
  row mixed cgal "$r" "$j" "$($PY "$ROOT/bench/segment/score_labels.py" "$WORK/mixed.ply" "$WORK/mcgal.labels")"
  j=$("$RUNNER" ransac "$WORK/fandisk.ply" all $F_SPACING $F_CLUSTER $NORMAL $F_MIN $PROB "$WORK/fps.labels")
  row fandisk pointsurf "$r" "$j" "$(assigned "$j" "$F_N")"
  j=$("$CGAL_BIN" "$WORK/fandisk.bin" $F_SPACING $F_CLUSTER $NORMAL $F_MIN $PROB all "$WORK/fcgal.labels")
  row fandisk cgal "$r" "$j" "$(assigned "$j" "$F_N")"
  j=$("$RUNNER" euclidean "$WORK/scene.ply" $CLUSTER "$WORK/psc.labels")
  row cluster pointsurf "$r" "$j" "$($PY "$ROOT/bench/segment/score_labels.py" "$WORK/scene.ply" "$WORK/psc.labels")"
  j=$($PY "$ROOT/bench/segment/open3d_segment.py" dbscan "$WORK/scene.ply" $CLUSTER "$WORK/o3dc.labels")
  row cluster open3d "$r" "$j" "$($PY "$ROOT/bench/segment/score_labels.py" "$WORK/scene.ply" "$WORK/o3dc.labels")"
done
$PY - "$CSV" "$COMMIT" <<'PYEOF'
import csv, statistics, sys
rows = [r for r in csv.DictReader(open(sys.argv[1])) if r["commit"] == sys.argv[2]]
print("| task | tool | median s | primitives / segments | completeness | recovered (>= 95 %) |")
print("|---|---|---|---|---|---|")
for task in ("ransac", "planes", "cluster", "building", "mixed", "fandisk"):
    for tool in sorted({r["tool"] for r in rows if r["task"] == task}):
        rs = [r for r in rows if r["task"] == task and r["tool"] == tool]
        print(f'| {task} | {tool} | {statistics.median(float(r["seconds"]) for r in rs):.3f} | {rs[-1]["primitives"]} | {rs[-1]["completeness"]} | {rs[-1]["recovered_95"]} |')
PYEOF
rm -rf "$WORK"
