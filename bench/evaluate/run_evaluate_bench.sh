#!/usr/bin/env bash
# Point-to-mesh distance: pointsurf against Open3D 0.16 (Debian's python3-open3d) in the same run.
#   bench/evaluate/run_evaluate_bench.sh [REPEATS] [LEVELS] [POINTS]   (default: 3 2 1000000)
# Mesh: CGAL's bunny00.off (libcgal-demo, 75408 triangles) split 1-to-4 LEVELS times (2: 1206528
# triangles, the surface unchanged). Queries: POINTS area-uniform samples (seed 1) moved along
# their face normal by a uniform offset in [-2%, 2%] of the diagonal. Each run is its own
# process; times include the hierarchy build (Embree's scene for Open3D), file reading excluded.
#   pointsurf unsigned  TriangleBvh + closest points (double)
#   pointsurf signed    mesh_distances, sign auto (pseudo-normals here: the bunny is manifold)
#   pointsurf winding   mesh_distances, sign from the winding number (the sign oracle)
#   open3d raycast      RaycastingScene.compute_distance (Embree, float32)
#   open3d raycast-signed  compute_signed_distance (0.16.1 casts no rays: never negative)
#   open3d cloud        compute_point_cloud_distance to the mesh's vertices (approximate)
# Peers of the hierarchy (bench/evaluate/mesh_distance_peers.cpp, same timing, unsigned, queries
# in the same Morton order and TBB blocks, exact double distances):
#   peers pointsurf     TriangleBvh::closest_near
#   peers embree        Embree 3 rtcPointQuery (float boxes) + pointsurf's exact double test
#                       (only where Debian's libembree-dev was installed at configure time)
#   peers cgal          CGAL AABB_tree<Simple_cartesian<double>> closest_point_and_primitive
# Whole process, each a process of its own, interleaved, wall seconds and peak RSS from
# /usr/bin/time (reading, hierarchy, distances, report, writing):
#   pointsurf-cli whole-unsigned  pointsurf evaluate MESH --reference CLOUD --sign unsigned --out OUT.ply
#   pointsurf-cli whole-signed    the same with the default sign (auto: pseudo-normals here)
#   open3d-script whole-unsigned  bench/evaluate/open3d_whole_process.py MESH CLOUD OUT.ply
# Memory: peak RSS of the process; for Open3D also net of the interpreter + numpy + open3d
# baseline measured in the same process before reading. Raw rows go to
# bench/results/evaluate_distance.csv (commit, date), the agreement figures to
# bench/results/evaluate_agreement.json.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
REPEATS="${1:-3}"
LEVELS="${2:-2}"
POINTS="${3:-1000000}"
PY=/usr/bin/python3
RUNNER="$BUILD_DIR/bench/mesh_distance_runner"
PEERS="$BUILD_DIR/bench/mesh_distance_peers"
CLI="${CLI:-$BUILD_DIR/pointsurf}"  # CLI=... times another build of the command
WORK="$ROOT/bench/out/evaluate"
CSV="$ROOT/bench/results/evaluate_distance.csv"
mkdir -p "$WORK" "$ROOT/bench/results"
[ -x "$RUNNER" ] || { echo "build $RUNNER first (-DPOINTSURF_BUILD_BENCHMARKS=ON)" >&2; exit 1; }

if [ ! -f "$WORK/bunny00.off" ]; then
  tar xzf /usr/share/doc/libcgal-demo/data.tar.gz -C "$WORK" data/meshes/bunny00.off
  mv "$WORK/data/meshes/bunny00.off" "$WORK/bunny00.off"
  rm -rf "$WORK/data"
fi
MESH="$WORK/bunny_l${LEVELS}.ply"
CLOUD="$WORK/bunny_l${LEVELS}_${POINTS}.ply"
INFO="$WORK/bunny_l${LEVELS}_${POINTS}.json"
[ -f "$INFO" ] || "$RUNNER" prepare "$WORK/bunny00.off" "$LEVELS" "$MESH" "$POINTS" "$CLOUD" 1 > "$INFO"
DIAGONAL=$("$PY" -c "import json; print(json.load(open('$INFO'))['diagonal'])")

COMMIT=$(git -C "$ROOT" rev-parse --short HEAD)
DATE=$(date -u +%Y-%m-%dT%H:%M:%SZ)
[ -f "$CSV" ] || echo "commit,date,tool,mode,repeat,points,triangles,seconds,peak_rss_mb,baseline_rss_mb,net_rss_mb" > "$CSV"
row() {  # tool mode repeat json
  "$PY" - "$@" <<'PYEOF' >> "$CSV"
import json, sys
tool, mode, rep, text, commit, date = sys.argv[1:7]
r = json.loads(text)
base = r.get("baseline_rss_mb", 0.0)
print(f"{commit},{date},{tool},{mode},{rep},{r['points']},{r['triangles']},{r['seconds']},{r['peak_rss_mb']},{base},{round(r['peak_rss_mb'] - base, 1)}")
PYEOF
}
# One whole process: wall seconds and peak RSS as the JSON that row() reads.
whole() {  # label command...
  local label=$1; shift
  /usr/bin/time -f "%e %M" -o "$WORK/time.txt" "$@" > /dev/null 2>> "$WORK/whole.log"
  read -r secs kb < "$WORK/time.txt"
  echo "{\"points\": $POINTS_N, \"triangles\": $TRIANGLES_N, \"seconds\": $secs, \"peak_rss_mb\": $(( kb / 1024 ))}"
}
POINTS_N=$("$PY" -c "import json; print(json.load(open('$INFO'))['points'])")
TRIANGLES_N=$("$PY" -c "import json; print(json.load(open('$INFO'))['triangles'])")
PEER_TOOLS="pointsurf cgal"
"$PEERS" "$MESH" "$CLOUD" embree "$WORK/peer_probe.bin" > /dev/null 2>&1 && PEER_TOOLS="pointsurf embree cgal"
echo "load before: $(uptime)" >&2
for rep in $(seq 1 "$REPEATS"); do
  out=$(whole pointsurf-unsigned "$CLI" evaluate "$MESH" --reference "$CLOUD" --sign unsigned --out "$WORK/ps_whole_unsigned.ply")
  echo "pointsurf-cli whole-unsigned: $out" >&2
  row pointsurf-cli whole-unsigned "$rep" "$out" "$COMMIT" "$DATE"
  out=$(whole open3d "$PY" "$ROOT/bench/evaluate/open3d_whole_process.py" "$MESH" "$CLOUD" "$WORK/o3d_whole.ply")
  echo "open3d-script whole-unsigned: $out" >&2
  row open3d-script whole-unsigned "$rep" "$out" "$COMMIT" "$DATE"
  out=$(whole pointsurf-signed "$CLI" evaluate "$MESH" --reference "$CLOUD" --out "$WORK/ps_whole_signed.ply")
  echo "pointsurf-cli whole-signed: $out" >&2
  row pointsurf-cli whole-signed "$rep" "$out" "$COMMIT" "$DATE"
  for tool in $PEER_TOOLS; do
    out=$("$PEERS" "$MESH" "$CLOUD" "$tool" "$WORK/peer_$tool.bin")
    echo "peers $tool: $out" >&2
    row "peer-$tool" unsigned "$rep" "$out" "$COMMIT" "$DATE"
  done
done
echo "load after: $(uptime)" >&2
for rep in $(seq 1 "$REPEATS"); do
  for mode in unsigned signed winding; do
    out=$("$RUNNER" time "$MESH" "$CLOUD" "$mode" "$WORK/ours_$mode.bin")
    echo "pointsurf $mode: $out" >&2
    row pointsurf "$mode" "$rep" "$out" "$COMMIT" "$DATE"
  done
  for mode in raycast raycast-signed cloud; do
    out=$("$PY" "$ROOT/bench/evaluate/open3d_distance.py" "$MESH" "$CLOUD" "$mode" "$WORK/o3d_$mode.npy")
    echo "open3d $mode: $out" >&2
    row open3d "$mode" "$rep" "$out" "$COMMIT" "$DATE"
  done
done
"$PY" "$ROOT/bench/evaluate/compare_distances.py" "$DIAGONAL" "$WORK/ours_unsigned.bin" "$WORK/ours_signed.bin" "$WORK/ours_winding.bin" \
  "$WORK/o3d_raycast.npy" "$WORK/o3d_raycast-signed.npy" | "$PY" -c "import json,sys; r=json.load(sys.stdin); r.update(commit='$COMMIT', date='$DATE', diagonal=$DIAGONAL); print(json.dumps(r, indent=2))" \
  > "$ROOT/bench/results/evaluate_agreement.json"
cat "$ROOT/bench/results/evaluate_agreement.json" >&2
# The peers' distances against pointsurf's (max absolute difference, diagonal units).
for tool in $PEER_TOOLS; do
  "$PY" -c "import numpy as np, sys; a=np.fromfile('$WORK/peer_pointsurf.bin'); b=np.fromfile('$WORK/peer_$tool.bin'); print('peer $tool: max |d - pointsurf| / diagonal', float(np.abs(a-b).max())/$DIAGONAL)" >&2
done
# Medians per tool and mode of this run, and the whole-process ratios pair by pair.
"$PY" - "$CSV" "$COMMIT" "$DATE" <<'PYEOF' >&2
import csv, statistics, sys
rows = [r for r in csv.DictReader(open(sys.argv[1])) if r["commit"] == sys.argv[2] and r["date"] == sys.argv[3]]
for key in sorted({(r["tool"], r["mode"]) for r in rows}):
    sel = [r for r in rows if (r["tool"], r["mode"]) == key]
    print(f"{key[0]:9} {key[1]:15} median {statistics.median(float(r['seconds']) for r in sel):8.3f} s  "
          f"peak {statistics.median(float(r['peak_rss_mb']) for r in sel):7.1f} MB  net {statistics.median(float(r['net_rss_mb']) for r in sel):7.1f} MB")
o3d = {r["repeat"]: float(r["seconds"]) for r in rows if (r["tool"], r["mode"]) == ("open3d-script", "whole-unsigned")}
for mode in ("whole-unsigned", "whole-signed"):
    ratios = sorted(float(r["seconds"]) / o3d[r["repeat"]] for r in rows if (r["tool"], r["mode"]) == ("pointsurf-cli", mode) and r["repeat"] in o3d)
    if ratios:
        print(f"pointsurf {mode} / open3d whole-unsigned, pair by pair: median {statistics.median(ratios):.3f} (min {ratios[0]:.3f}, max {ratios[-1]:.3f})")
PYEOF
