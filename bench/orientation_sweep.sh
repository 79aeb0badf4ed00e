#!/usr/bin/env bash
# Orientation on CGAL's example scans that carry normals, pointsurf next to Open3D.
#   bench/orientation_sweep.sh        (after ./pointsurf.sh bench has installed the packages)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
OUT="$ROOT/bench/out/orientation"
mkdir -p "$OUT"
tar xzf /usr/share/doc/libcgal-demo/data.tar.gz -C "$OUT" data/points_3
scans=(ball.ply building.ply fin90_with_PCA_normals.xyz hippo1.ply hippo2.ply kitten.xyz oni.ply
       point_set_3.xyz sphere926.pwn sphere_1k.xyz sphere_20k_normal.xyz spheres.ply)
inputs=()
for s in "${scans[@]}"; do
  # pointsurf reads the normals of every format; Open3D needs them in a PLY.
  "$BUILD_DIR/pointsurf" convert "$OUT/data/points_3/$s" "$OUT/${s%.*}.ply" --quiet
  inputs+=("$OUT/${s%.*}.ply")
done
/usr/bin/python3 "$ROOT/bench/orientation_sweep.py" "$BUILD_DIR/pointsurf" "${inputs[@]}"
