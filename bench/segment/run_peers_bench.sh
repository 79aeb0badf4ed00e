#!/bin/bash
# Region growing against PCL's RegionGrowing, Euclidean clustering against Open3D's
# cluster_dbscan: time and agreement, interleaved runs, medians of REPEATS.
#   region:  pointsurf segment_region_growing vs pcl::RegionGrowing (bench/segment/
#            pcl_region_growing.cpp, built by bench/CMakeLists.txt where libpcl-dev is found):
#            same normals, k 16 (+ the point itself), 8 degrees, variation 0.05, min 10 points
#            (pointsurf's defaults), no feature barriers
#   cluster: pointsurf segment_euclidean vs Open3D cluster_dbscan (min_points 1), same radius
# Inputs: the 1M-point primitive scene (make_scene.py, truth labels), CGAL's demo building.ply
# (100k, its normals, segment_index planes as truth) and, real and unseen, the demo's aerial b9
# tile (22 300 points, normals by `pointsurf normals`, no segment truth).
# Agreement (agreement.py): adjusted Rand index between the tools over the points both assign,
# size-weighted best-match IoU of pointsurf's segments in the peer's, and against the truth.
# Writes bench/results/segment_peers.csv (raw runs) and prints a Markdown table.
#   bench/segment/run_peers_bench.sh [BUILD_DIR] [REPEATS]
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${1:-$ROOT/build}
REPEATS=${2:-3}
PY=/usr/bin/python3
SEG=$ROOT/bench/segment
RUNNER="$BUILD/bench/segment_runner"
PCL_BIN="$BUILD/bench/pcl_region_growing"
[ -x "$PCL_BIN" ] || { echo "run_peers_bench.sh: $PCL_BIN missing (install libpcl-dev, rebuild with -DPOINTSURF_BUILD_BENCHMARKS=ON)" >&2; exit 2; }
WORK=$(mktemp -d /tmp/pointsurf_peers_bench.XXXX)
$PY "$SEG/make_scene.py" 1000000 0.005 "$WORK/scene.ply" "$WORK/scene.bin" > /dev/null
tar xzf /usr/share/doc/libcgal-demo/data.tar.gz -C "$WORK" data/points_3/building.ply data/points_3/b9_training.ply
$PY "$SEG/building_case.py" "$WORK/data/points_3/building.ply" "$WORK/building.ply" "$WORK/building.bin"
"$BUILD/pointsurf" normals "$WORK/data/points_3/b9_training.ply" "$WORK/b9_normals.ply" > /dev/null
$PY "$SEG/normals_case.py" "$WORK/b9_normals.ply" "$WORK/b9.ply" "$WORK/b9.bin"
K=16 ANGLE=8 VARIATION=0.05 MIN=10
# Cluster radii: 0.05 on the scene (as run_segment_bench.sh), 3 mean spacings on b9 (0.6596).
declare -A RADIUS=([scene]=0.05 [b9]=1.9788)
CSV="$ROOT/bench/results/segment_peers.csv"
COMMIT=$(git -C "$ROOT" rev-parse --short HEAD)
DATE=$(date -u +%Y-%m-%dT%H:%M:%SZ)
MACHINE="$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
[ -f "$CSV" ] || echo "commit,date,machine,load,input,task,tool,run,seconds,cpu_seconds,segments,unassigned,ari_other,iou_in_other,truth_ari,truth_iou" > "$CSV"
row() {  # input task tool run json agreement_json
  local load; load=$(cut -d' ' -f1 /proc/loadavg)
  $PY - "$COMMIT" "$DATE" "$MACHINE" "$load" "$@" >> "$CSV" <<'PYEOF'
import json, sys
c, d, m, load, inp, task, tool, run, line, agree = sys.argv[1:]
j, a = json.loads(line), json.loads(agree)
print(f'{c},{d},"{m}",{load},{inp},{task},{tool},{run},{j["seconds"]},{j.get("cpu_seconds", "")},{j["segments"]},{j["unassigned"]},'
      f'{a["ari"]},{a["iou_a_in_b"]},{a.get("truth_ari", "")},{a.get("truth_iou_weighted", "")}')
PYEOF
}
agree() { $PY "$SEG/agreement.py" "$@"; }
for r in $(seq 1 "$REPEATS"); do
  echo "run $r/$REPEATS (load $(cut -d' ' -f1 /proc/loadavg))" >&2
  for input in scene building b9; do
    ps=$("$RUNNER" region "$WORK/$input.ply" $K $ANGLE $VARIATION $MIN "$WORK/ps.labels")
    pcl=$("$PCL_BIN" "$WORK/$input.bin" $K $ANGLE $VARIATION $MIN "$WORK/pcl.labels")
    row "$input" region pointsurf "$r" "$ps" "$(agree "$WORK/ps.labels" "$WORK/pcl.labels" "$WORK/$input.ply")"
    row "$input" region pcl "$r" "$pcl" "$(agree "$WORK/pcl.labels" "$WORK/ps.labels" "$WORK/$input.ply")"
  done
  for input in scene b9; do
    ps=$("$RUNNER" euclidean "$WORK/$input.ply" "${RADIUS[$input]}" "$WORK/ps.labels")
    o3d=$($PY "$SEG/open3d_segment.py" dbscan "$WORK/$input.ply" "${RADIUS[$input]}" "$WORK/o3d.labels")
    row "$input" cluster pointsurf "$r" "$ps" "$(agree "$WORK/ps.labels" "$WORK/o3d.labels" "$WORK/$input.ply")"
    row "$input" cluster open3d "$r" "$o3d" "$(agree "$WORK/o3d.labels" "$WORK/ps.labels" "$WORK/$input.ply")"
  done
done
$PY - "$CSV" "$COMMIT" <<'PYEOF'
import csv, statistics, sys
rows = [r for r in csv.DictReader(open(sys.argv[1])) if r["commit"] == sys.argv[2]]
print("| input | task | tool | median s | median CPU s | time / peer's | CPU / peer's | segments | unassigned | ARI with the other | IoU in the other | ARI with truth | IoU with truth |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
med = lambda rs, k: statistics.median(float(r[k]) for r in rs) if rs and rs[0][k] else float("nan")
for inp in ("scene", "building", "b9"):
    for task in ("region", "cluster"):
        tools = sorted({r["tool"] for r in rows if r["input"] == inp and r["task"] == task})
        if not tools:
            continue
        peer = [r for r in rows if r["input"] == inp and r["task"] == task and r["tool"] != "pointsurf"]
        for tool in tools:
            rs = [r for r in rows if r["input"] == inp and r["task"] == task and r["tool"] == tool]
            ratio = f'{med(rs, "seconds") / med(peer, "seconds"):.2f}x' if tool == "pointsurf" else ""
            # Open3D reports no CPU time (its Python process runs other threads).
            cpu = f'{med(rs, "cpu_seconds") / med(peer, "cpu_seconds"):.2f}x' if tool == "pointsurf" and peer[0]["cpu_seconds"] else ""
            last = rs[-1]
            print(f'| {inp} | {task} | {tool} | {med(rs, "seconds"):.3f} | {med(rs, "cpu_seconds"):.3f} | {ratio} | {cpu} | {last["segments"]} | {last["unassigned"]} | '
                  f'{last["ari_other"]} | {last["iou_in_other"]} | {last["truth_ari"] or "-"} | {last["truth_iou"] or "-"} |')
PYEOF
rm -rf "$WORK"
