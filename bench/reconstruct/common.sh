# SPDX-License-Identifier: GPL-3.0-or-later
# Shared set-up of the reconstruction benchmarks, sourced by run_*_bench.sh after they set
# WORK_NAME: paths, the reference mesh (CGAL's MESH.off from libcgal-demo, default armadillo)
# and its area-uniform samples with true normals (seed 1, bench/out/MESH_N.ply).
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
MESH="${MESH:-armadillo}"
OUT="$ROOT/bench/out"
WORK="$OUT/$WORK_NAME"
PY=/usr/bin/python3
METRICS="$BUILD_DIR/bench/mesh_metrics_runner"
mkdir -p "$WORK"

if [ ! -f "$OUT/$MESH.off" ]; then
  tar xzf /usr/share/doc/libcgal-demo/data.tar.gz -C "$OUT" "data/meshes/$MESH.off"
  mv "$OUT/data/meshes/$MESH.off" "$OUT/$MESH.off"
  rm -rf "$OUT/data"
fi

# sample_cloud N: prints the path of the N-point sample, making it first when missing.
sample_cloud() {
  local cloud="$OUT/${MESH}_$1.ply"
  [ -f "$cloud" ] || "$BUILD_DIR/bench/pointsurf_bench" sample "$OUT/$MESH.off" "$1" "$cloud" 1
  echo "$cloud"
}
