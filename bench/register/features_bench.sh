#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Descriptors and global alignment against Open3D on the same prepared pairs:
# pointsurf compute_descriptors (FPFH, PFH) + align_global next to Open3D's compute_fpfh_feature
# + registration_ransac_based_on_feature_matching, same voxel-downsampled clouds with the same
# normals (written once by features_open3d.py prep-*), same radius (5 voxels, 100 neighbours),
# max correspondence distance (1.5 voxels), edge-length ratio 0.9, 100000 trials, confidence 0.999.
#   bench/register/features_bench.sh [REPEATS] [STARTS]     (default 3 repeats, 3 start poses)
# Pairs (all made here from libcgal-demo's data.tar.gz and data/kitten.xyz):
#   hippo   hippo2 onto hippo1 (a real pair; reference pose: best of 20 Open3D RANSAC + ICP
#           runs), voxel 0.01, source turned by STARTS seeded rotations;
#   kitten  data/kitten.xyz split at random into two scans, each cropped to 85 % (about 70 %
#           in common), noise 0.2 spacings, STARTS seeded motions, voxel 0.02;
#   bunny   bunny00.off sampled at 400k points, made into two scans the same way, voxel 0.006
#           (about 45k points a scan: the scale row), the first start only.
# Runs are interleaved (pointsurf, Open3D, pointsurf, ...) and each run's 1-minute load is
# recorded. Seeds: run r uses seed r for both tools. Writes bench/results/register_features.csv
# (appends) and prints the medians; needs $BUILD_DIR/bench/features_register_runner
# (-DPOINTSURF_BUILD_BENCHMARKS=ON) and python3-open3d under /usr/bin/python3.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
REPEATS="${1:-3}"
STARTS="${2:-3}"
RUNNER="$BUILD_DIR/bench/features_register_runner"
PY=/usr/bin/python3
HERE="$ROOT/bench/register"
WORK="$ROOT/bench/out/register_features"
CSV="$ROOT/bench/results/register_features.csv"
mkdir -p "$WORK"

if [ ! -x "$RUNNER" ]; then
  echo "error: $RUNNER not found: configure with -DPOINTSURF_BUILD_BENCHMARKS=ON and build features_register_runner" >&2
  exit 1
fi
if ! "$PY" -c 'import open3d, numpy' 2> /dev/null; then
  echo "error: Open3D and numpy must be importable by $PY (python3-open3d)" >&2
  exit 1
fi
TAR=/usr/share/doc/libcgal-demo/data.tar.gz
if [ ! -f "$WORK/hippo1.ply" ]; then
  [ -f "$TAR" ] || { echo "error: $TAR missing (apt-get install libcgal-demo)" >&2; exit 1; }
  tar xzf "$TAR" -C "$WORK" data/points_3/hippo1.ply data/points_3/hippo2.ply data/meshes/bunny00.off
  mv "$WORK"/data/points_3/hippo?.ply "$WORK"/data/meshes/bunny00.off "$WORK"/
  rm -rf "$WORK/data"
fi

declare -A VOXEL=([hippo]=0.01 [kitten]=0.02 [bunny]=0.006)
declare -A NSTART=([hippo]=$STARTS [kitten]=$STARTS [bunny]=1)
for d in hippo kitten bunny; do
  mkdir -p "$WORK/$d"
  if [ ! -f "$WORK/$d/truth_$((${NSTART[$d]} - 1)).json" ]; then
    echo "[prep] $d" >&2
    case $d in
      hippo) "$PY" "$HERE/features_open3d.py" prep-hippo "$WORK/hippo1.ply" "$WORK/hippo2.ply" "${VOXEL[$d]}" "${NSTART[$d]}" "$WORK/$d" ;;
      kitten) "$PY" "$HERE/features_open3d.py" prep-mesh "$ROOT/data/kitten.xyz" 0 "${VOXEL[$d]}" "${NSTART[$d]}" "$WORK/$d" ;;
      bunny) "$PY" "$HERE/features_open3d.py" prep-mesh "$WORK/bunny00.off" 400000 "${VOXEL[$d]}" "${NSTART[$d]}" "$WORK/$d" ;;
    esac
  fi
done

COMMIT="$(git -C "$ROOT" rev-parse --short HEAD)"
DATE="$(date -u +%Y-%m-%dT%H:%M:%SZ)"
MACHINE="$(nproc) cores $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
RAW="$WORK/runs.jsonl"
: > "$RAW"
load() { cut -d' ' -f1 /proc/loadavg; }
record() {  # JSON line on stdin; dataset start run load
  "$PY" -c 'import json, sys
r = json.loads(sys.stdin.read()); r.update(dataset=sys.argv[1], start=int(sys.argv[2]), run=int(sys.argv[3]), load=float(sys.argv[4]))
print(json.dumps(r))' "$@" >> "$RAW"
}

for ((r = 1; r <= REPEATS; r++)); do
  for d in hippo kitten bunny; do
    for ((k = 0; k < ${NSTART[$d]}; k++)); do
      args=("$WORK/$d/source_$k.ply" "$WORK/$d/target.ply" "$WORK/$d/truth_$k.json" "${VOXEL[$d]}" "$r")
      pfh=pfh
      [ "$d" = bunny ] && [ "$r" != 1 ] && pfh=""
      echo "[run $r] $d start $k: pointsurf, open3d" >&2
      l=$(load); "$RUNNER" "${args[@]}" $pfh | record "$d" "$k" "$r" "$l"
      l=$(load); "$PY" "$HERE/features_open3d.py" run "${args[@]}" | record "$d" "$k" "$r" "$l"
    done
  done
done

"$PY" "$HERE/features_summary.py" "$RAW" "$CSV" "$COMMIT" "$DATE" "$MACHINE"
