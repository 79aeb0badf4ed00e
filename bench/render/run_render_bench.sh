#!/usr/bin/env bash
# Render time and peak memory at 100k and 1M points and triangles (bench/render/render_runner.cpp):
# a torus at x ~ 596,648 m, 1024x768 pixels, 3x3 samples per pixel, median of 3 renders, one
# process per configuration. Appends rows to bench/results/render.csv.
#   bash bench/render/run_render_bench.sh [BUILD_DIR]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD="${1:-$ROOT/build}"
CSV="$ROOT/bench/results/render.csv"
[ -f "$CSV" ] || echo "commit,date,machine,load1,kind,points,triangles,size,supersample,field,render_s,png_s,cpu_s,png_bytes,peak_rss_mb" > "$CSV"
commit="$(git -C "$ROOT" rev-parse --short HEAD)"
machine="$(nproc) cores $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
for kind in mesh points; do
  for n in 100000 1000000; do
    for field in "" deviation; do
      load="$(cut -d' ' -f1 /proc/loadavg)"
      line="$("$BUILD/bench/render_runner" "$kind" "$n" 1024x768 3 3 $field)"
      echo "$line" >&2
      python3 -c "import json,sys; r=json.loads(sys.argv[1]); print(','.join(str(x) for x in [sys.argv[2], sys.argv[3], '\"'+sys.argv[4]+'\"', sys.argv[5], r['kind'], r['points'], r['triangles'], r['size'], r['supersample'], r['field'], r['render_s'], r['png_s'], r['cpu_s'], r['png_bytes'], r['peak_rss_mb']]))" \
        "$line" "$commit" "$(date -u +%FT%TZ)" "$machine" "$load" >> "$CSV"
    done
  done
done
