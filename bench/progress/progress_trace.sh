#!/usr/bin/env bash
# Progress that looks alive (issue 28 item 8): runs `pointsurf reconstruct --method poisson` and
# `pointsurf evaluate` on a 1M-point cloud with POINTSURF_PROGRESS_TRACE and prints, per stage,
# the longest gap between progress calls and the largest |reported share - elapsed share|.
#   bench/progress/progress_trace.sh [POINTSURF] [CLOUD.xyz] [WORKDIR]
# CLOUD defaults to 1M points sampled on CGAL's armadillo (libcgal-demo's data), with normals.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
cli=${1:-$here/../../build/pointsurf}
work=${3:-/tmp/pointsurf_progress}
mkdir -p "$work"
cloud=${2:-$work/armadillo_1m.xyz}
if [[ ! -f $cloud ]]; then
  tar xzf /usr/share/doc/libcgal-demo/data.tar.gz -C "$work" data/meshes/armadillo.off
  python3 "$here/sample_mesh.py" "$work/data/meshes/armadillo.off" 1000000 "$cloud"
fi
POINTSURF_PROGRESS_TRACE=$work/poisson.trace "$cli" reconstruct "$cloud" "$work/poisson.ply" --method poisson --quiet
POINTSURF_PROGRESS_TRACE=$work/evaluate.trace "$cli" evaluate "$work/poisson.ply" --reference "$cloud" --quiet
"$cli" info "$work/poisson.ply" | head -3
python3 "$here/trace_summary.py" "$work/poisson.trace" "$work/evaluate.trace"
