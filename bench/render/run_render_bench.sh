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

# The peer, interleaved with ours in the same minutes: Mesa's llvmpipe through OSMesa
# (bench/render/osmesa_peer.c; needs libosmesa6-dev), the same torus at 3x the size (our 3x3
# supersampling, without its downsampling) and at 1x. Medians of 3 processes each; rows in
# bench/results/render_peer.csv.
if [ -f /usr/include/GL/osmesa.h ]; then
  PEER="$(mktemp -d)/osmesa_peer"
  cc -O2 "$ROOT/bench/render/osmesa_peer.c" -o "$PEER" -lOSMesa -lm
  PCSV="$ROOT/bench/results/render_peer.csv"
  [ -f "$PCSV" ] || echo "commit,date,machine,load1,kind,n,ours_render_s,osmesa_3x_total_s,osmesa_3x_draw_s,osmesa_1x_total_s" > "$PCSV"
  for kind in mesh points; do
    for n in 100000 1000000; do
      ours=(); o3=(); d3=(); o1=()
      for rep in 1 2 3; do
        ours+=("$("$BUILD/bench/render_runner" "$kind" "$n" 1024x768 3 1 | python3 -c 'import json,sys; print(json.load(sys.stdin)["render_s"])')")
        line="$("$PEER" "$kind" "$n" 1024 768 3)"
        o3+=("$(echo "$line" | python3 -c 'import json,sys; print(json.load(sys.stdin)["total_s"])')")
        d3+=("$(echo "$line" | python3 -c 'import json,sys; print(json.load(sys.stdin)["draw_s"])')")
        o1+=("$("$PEER" "$kind" "$n" 1024 768 1 | python3 -c 'import json,sys; print(json.load(sys.stdin)["total_s"])')")
      done
      med() { printf '%s\n' "$@" | sort -g | sed -n 2p; }
      row="$commit,$(date -u +%FT%TZ),\"$machine\",$(cut -d' ' -f1 /proc/loadavg),$kind,$n,$(med "${ours[@]}"),$(med "${o3[@]}"),$(med "${d3[@]}"),$(med "${o1[@]}")"
      echo "$row" >&2
      echo "$row" >> "$PCSV"
    done
  done
fi
