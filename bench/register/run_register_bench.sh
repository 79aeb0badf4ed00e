#!/bin/bash
# Registration benchmark (issue 20), interleaved rounds, medians of REPEATS:
#   icp:      pointsurf icp (point / plane, with and without the normal-angle check) vs Open3D
#             registration_icp (default threads and one thread) and PCL pcl_icp, same pairs,
#             start, max correspondence distance and iteration cap (icp_bench.py says which)
#   pipeline: voxel grid + normals + FPFH + RANSAC + ICP, per step and in total, vs Open3D's same
#             recipe with the same voxel size, radii, RANSAC cap and confidence (icp_pipeline.py)
# Writes raw rows to bench/results/register.csv (commit, date, machine, load) and prints a
# Markdown table.
#   bench/register/run_register_bench.sh [BUILD_DIR] [REPEATS]
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${1:-$ROOT/build}
REPEATS=${2:-5}
PY=/usr/bin/python3
WORK=$(mktemp -d /tmp/pointsurf_register_bench.XXXX)
tar xzf /usr/share/doc/libcgal-demo/data.tar.gz -C "$WORK" data/points_3/hippo1.ply data/points_3/hippo2.ply data/meshes/armadillo.off
CSV="$ROOT/bench/results/register.csv"
COMMIT=$(git -C "$ROOT" rev-parse --short HEAD)
DATE=$(date -u +%Y-%m-%dT%H:%M:%SZ)
MACHINE="$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
$PY "$ROOT/bench/register/icp_bench.py" "$BUILD" "$REPEATS" "$WORK/icp" "$WORK/data/points_3/hippo1.ply" "$WORK/data/points_3/hippo2.ply" \
  "$ROOT/data/kitten.xyz" "$WORK/data/meshes/armadillo.off" "$CSV" "$COMMIT" "$DATE" "$MACHINE"
if [ ! -x "$BUILD/bench/icp_pipeline_runner" ]; then
  echo "no $BUILD/bench/icp_pipeline_runner: the pipeline rows need register/ features and align" >&2
  rm -rf "$WORK"
  exit 0
fi
$PY "$ROOT/bench/register/icp_pipeline.py" "$BUILD" "$REPEATS" "$WORK/pipeline" "$WORK/data/points_3/hippo1.ply" \
  "$WORK/data/points_3/hippo2.ply" "$ROOT/data/kitten.xyz" "$CSV" "$COMMIT" "$DATE" "$MACHINE"
rm -rf "$WORK"
