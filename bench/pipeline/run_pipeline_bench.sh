#!/usr/bin/env bash
# The demo chain (clean, normals, features, simplify, reconstruct) as one `pointsurf run`
# against the same five stages as separate commands with intermediate PLY files.
#   bench/pipeline/run_pipeline_bench.sh [REPEATS]     (default 3)
# Clouds: the shipped scans and a 1M-point cloud sampled (bench/pointsurf_bench sample, built by
# ./pointsurf.sh bench) from the kitten mesh the demo pipeline builds. Writes
# bench/results/pipeline_chain.csv (cloud, points, mode, repeat, seconds, peak_rss_mb) and says
# whether both ways give the same mesh, byte for byte.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
CLI="$BUILD_DIR/pointsurf"
SAMPLER="${SAMPLER:-$BUILD_DIR/bench/pointsurf_bench}"
REPEATS="${1:-3}"
OUT="$ROOT/bench/out/pipeline"
CSV="$ROOT/bench/results/pipeline_chain.csv"
mkdir -p "$OUT" "$(dirname "$CSV")"

clouds=("$ROOT/data/b9_training.ply" "$ROOT/data/kitten.xyz")
big="$OUT/kitten_1m.ply"
if [ ! -f "$big" ]; then
  (cd "$ROOT" && mkdir -p out && "$CLI" run examples/kitten_mesh.json --quiet)
  "$SAMPLER" sample "$ROOT/out/kitten_mesh.ply" 1000000 "$big" 1 >/dev/null
fi
clouds+=("$big")

# Runs "$@" under /usr/bin/time; prints "seconds peak_rss_mb".
timed() {
  local t0 t1 kb
  t0=$(date +%s.%N)
  /usr/bin/time -f %M -o "$OUT/time.txt" "$@" >/dev/null 2>"$OUT/stderr.txt" || { cat "$OUT/stderr.txt" >&2; exit 1; }
  t1=$(date +%s.%N)
  kb=$(tail -1 "$OUT/time.txt")
  echo "$(echo "$t1 - $t0" | bc -l) $(echo "$kb / 1024" | bc -l)"
}

echo "cloud,points,mode,repeat,seconds,peak_rss_mb" > "$CSV"
for cloud in "${clouds[@]}"; do
  name=$(basename "${cloud%.*}")
  points=$("$CLI" info "$cloud" --json | sed -n 's/.*"points": \([0-9]*\).*/\1/p' | head -1)
  cat > "$OUT/$name.json" <<JSON
["$cloud", {"type": "clean", "method": "sor"}, {"type": "normals", "orient": "mst"}, {"type": "features"},
 {"type": "simplify", "method": "regional", "ratio": 0.25}, {"type": "reconstruct", "method": "triangulate"}, "$OUT/${name}_run.ply"]
JSON
  for ((r = 1; r <= REPEATS; r++)); do
    read -r s m < <(timed "$CLI" run "$OUT/$name.json" --quiet)
    echo "$name,$points,run,$r,$s,$m" >> "$CSV"
    total=0; peak=0
    for step in "clean $cloud $OUT/${name}_1.ply --method sor" \
                "normals $OUT/${name}_1.ply $OUT/${name}_2.ply --orient mst" \
                "features $OUT/${name}_2.ply $OUT/${name}_3.ply" \
                "simplify $OUT/${name}_3.ply $OUT/${name}_4.ply --method regional --ratio 0.25" \
                "reconstruct $OUT/${name}_4.ply $OUT/${name}_commands.ply --method triangulate"; do
      # shellcheck disable=SC2086
      read -r s m < <(timed "$CLI" $step --quiet)
      total=$(echo "$total + $s" | bc -l)
      peak=$(echo "if ($m > $peak) $m else $peak" | bc -l)
    done
    echo "$name,$points,commands,$r,$total,$peak" >> "$CSV"
    echo "[$name] repeat $r done" >&2
  done
  if cmp -s "$OUT/${name}_run.ply" "$OUT/${name}_commands.ply"; then echo "[$name] same mesh both ways" >&2
  else echo "[$name] the meshes differ (intermediate files round float32 fields)" >&2; fi
done
echo "wrote $CSV" >&2
