#!/usr/bin/env bash
# Screened Poisson: pointsurf against Open3D 0.16 (create_from_point_cloud_poisson, PoissonRecon
# inside) and PCL (pcl_poisson_reconstruction) in the same run, on the same clouds and normals.
#   bench/reconstruct/run_poisson_bench.sh [MESHES] [SIZES] [DEPTHS] [REPEATS]
#   (default: "elephant fandisk" 100000 "8 9 10" 3; TOOLS="pointsurf open3d pcl", KINDS="clean noisy",
#   PEER_LIMIT=900 s)
# Clouds: area-uniform samples (seed 1) of CGAL's MESH.off (libcgal-demo; elephant is smooth,
# fandisk a CAD part with sharp edges) with the true face normals, clean and noisy (Gaussian noise
# of 0.25 % of the bounding-box diagonal, plus 1 % outliers in the box with random normals:
# bench/reconstruct/poisson_clouds.py). Every tool runs at its defaults but the depth, untrimmed.
# Runs are interleaved (run r of every tool before run r + 1) and the table shows medians of
# REPEATS runs (one run at 1M points and more). Seconds: pointsurf the whole process (reading,
# kd-tree, solve, extraction, writing), Open3D the call alone, PCL its "Computing" figure (reading
# and writing excluded). Peak MB: the whole process (/usr/bin/time); for Open3D also the peak net
# of the interpreter and the loaded cloud. Quality: bench/reconstruct/mesh_metrics_runner (pointsurf's
# topology analysis and Chamfer / Hausdorff to the true mesh) on every tool's last output. The
# 1-minute load average is recorded with every run. Raw results: bench/results/reconstruct_poisson.csv
# (appended, with commit, date and machine).
# Needs: BUILD_DIR with pointsurf (the CLI), pointsurf_bench and mesh_metrics_runner built.
set -euo pipefail
WORK_NAME=poisson
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
MESHES="${1:-elephant fandisk}"
SIZES="${2:-100000}"
DEPTHS="${3:-8 9 10}"
REPEATS="${4:-3}"
TOOLS="${TOOLS:-pointsurf open3d pcl}"
KINDS="${KINDS:-clean noisy}"
PEER_LIMIT="${PEER_LIMIT:-900}"
CLI="${CLI:-$BUILD_DIR/pointsurf}"  # from another build: set COMMIT to name it
TIMING="$WORK/time.txt"

RESULTS="${RESULTS:-$WORK/results.jsonl}"
[ -n "${APPEND:-}" ] || : > "$RESULTS"
load1() { cut -d' ' -f1 /proc/loadavg; }
record() {  # record JSON_LINE KEY=VALUE...: adds the fields and appends the line to RESULTS
  local line=$1; shift
  "$PY" -c 'import json,sys
d = json.loads(sys.argv[1])
for kv in sys.argv[2:]:
    k, v = kv.split("=", 1)
    try: d[k] = json.loads(v)
    except ValueError: d[k] = v
print(json.dumps(d))' "$line" "$@" >> "$RESULTS"
}
time_fields() { read -r wall kb < "$TIMING"; echo "{\"process_seconds\": $wall, \"peak_rss_mb\": $("$PY" -c "print($kb/1024)")}"; }

for MESH in $MESHES; do
  if [ ! -f "$OUT/$MESH.off" ]; then
    tar xzf /usr/share/doc/libcgal-demo/data.tar.gz -C "$OUT" "data/meshes/$MESH.off"
    mv "$OUT/data/meshes/$MESH.off" "$OUT/$MESH.off"
    rm -rf "$OUT/data"
  fi
  for n in $SIZES; do
    clean=$(sample_cloud "$n")
    noisy="$WORK/${MESH}_${n}_noisy.ply"
    [ -f "$noisy" ] || "$PY" "$ROOT/bench/reconstruct/poisson_clouds.py" "$clean" "$noisy" "$WORK/${MESH}_${n}_clean.pcd" "$WORK/${MESH}_${n}_noisy.pcd"
    runs=$REPEATS
    [ "$n" -ge 1000000 ] && runs=1
    for kind in $KINDS; do
      cloud=$clean; [ "$kind" = noisy ] && cloud=$noisy
      for depth in $DEPTHS; do
        for ((r = 0; r < runs; r++)); do
          for tool in $TOOLS; do
            out="$WORK/${tool}_${MESH}_${kind}_${n}_d${depth}.ply"
            tags=(tool="$tool" mesh="$MESH" points="$n" kind="$kind" depth="$depth" run="$r" load1="$(load1)")
            echo "[$MESH $n $kind depth $depth] $tool run $((r + 1))/$runs (load $(load1))" >&2
            rm -f "$out"
            case $tool in
              pointsurf)
                if /usr/bin/time -f '%e %M' -o "$TIMING" "$CLI" reconstruct "$cloud" "$out" --method poisson --depth "$depth" > "$WORK/pointsurf.log" 2>&1; then
                  t=$(time_fields)
                  record "$t" "${tags[@]}" seconds="$("$PY" -c "import json; print(json.loads('$t')['process_seconds'])")"
                else
                  record '{}' "${tags[@]}" failed="$(tail -1 "$WORK/pointsurf.log" | tr -d '"=')"
                fi ;;
              open3d)
                if line=$(timeout "$PEER_LIMIT" /usr/bin/time -f '%e %M' -o "$TIMING" "$PY" "$ROOT/bench/reconstruct/poisson_open3d.py" "$cloud" "$depth" "$out" 2> /dev/null); then
                  t=$(time_fields)
                  record "$line" "${tags[@]}" process_seconds="$("$PY" -c "import json; print(json.loads('$t')['process_seconds'])")"
                else
                  record '{}' "${tags[@]}" failed="timeout ${PEER_LIMIT}s or error"
                fi ;;
              pcl)
                vtk="$WORK/pcl.vtk"
                if timeout "$PEER_LIMIT" /usr/bin/time -f '%e %M' -o "$TIMING" pcl_poisson_reconstruction "$WORK/${MESH}_${n}_${kind}.pcd" "$vtk" -depth "$depth" > "$WORK/pcl.log" 2>&1; then
                  t=$(time_fields)
                  # "Computing ...[Done, X ms]", possibly split by its "Vertex pair not in list" lines
                  ms=$(grep -o '\[Done, [0-9.]* ms\]' "$WORK/pcl.log" | head -1 | tr -dc '0-9.')
                  if [ -n "$ms" ]; then record "$t" "${tags[@]}" seconds="$("$PY" -c "print($ms/1000)")"
                  else record "$t" "${tags[@]}" seconds="$("$PY" -c "import json; print(json.loads('$t')['process_seconds'])")"; fi
                  pcl_vtk2ply "$vtk" "$out" > /dev/null
                else
                  record '{}' "${tags[@]}" failed="timeout ${PEER_LIMIT}s or error"
                fi ;;
            esac
          done
        done
        for tool in $TOOLS; do
          out="$WORK/${tool}_${MESH}_${kind}_${n}_d${depth}.ply"
          [ -f "$out" ] || continue
          m=$("$METRICS" "$out" "$OUT/$MESH.off")
          record "{\"metrics\": $m}" tool="$tool" mesh="$MESH" points="$n" kind="$kind" depth="$depth"
        done
      done
    done
  done
done

if [ -z "${COMMIT:-}" ]; then  # COMMIT names the build of CLI when it is not this checkout
  COMMIT=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
  git -C "$ROOT" diff --quiet HEAD -- src include 2>/dev/null || COMMIT="$COMMIT+dirty"
fi
PYTHONPATH="$ROOT/bench/reconstruct" "$PY" "$ROOT/bench/reconstruct/poisson_table.py" "$RESULTS" "${CSV:-$ROOT/bench/results/reconstruct_poisson.csv}" "$COMMIT" \
  | tee "$OUT/poisson.md"
echo "results: $OUT/poisson.md, bench/results/reconstruct_poisson.csv" >&2
