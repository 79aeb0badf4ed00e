#!/usr/bin/env bash
# LAZ decode and encode speed and compression ratio on a synthetic 10M-point airborne scan
# (bench/io/laz_runner.cpp, seeded), against laz-perf 0.0.7 (npm, WASM, in node) decoding the
# same file in the same run, interleaved, REPEATS times each.
#   bench/io/run_laz_bench.sh [POINTS] [REPEATS]      (defaults 10000000, 5)
# laz-perf comes from BUILD_DIR/npm (./pointsurf.sh build installs it). The npm package has no
# encoder, so encode speed is pointsurf's alone. Writes bench/results/io_laz.csv with the commit,
# date, machine and load average of each row.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
RUNNER="$BUILD_DIR/bench/laz_runner"
LAZPERF="$BUILD_DIR/npm/node_modules/laz-perf"
POINTS="${1:-10000000}"
REPEATS="${2:-5}"
OUT="$ROOT/bench/out/io"
CSV="$ROOT/bench/results/io_laz.csv"
mkdir -p "$OUT" "$(dirname "$CSV")"
[ -x "$RUNNER" ] || { echo "build laz_runner first (cmake --build build --target laz_runner)"; exit 1; }
[ -d "$LAZPERF" ] || npm install --prefix "$BUILD_DIR/npm" --no-audit --no-fund laz-perf@0.0.7 >/dev/null

commit="$(git -C "$ROOT" rev-parse --short HEAD)"
date="$(date -u +%Y-%m-%dT%H:%M:%SZ)"
machine="$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
load() { cut -d' ' -f1 /proc/loadavg; }
json() { python3 -c "import json,sys; print(json.loads(sys.argv[1])[sys.argv[2]])" "$1" "$2"; }

[ -f "$CSV" ] || echo "commit,date,machine,load,points,tool,measure,repeat,value,unit" > "$CSV"
row() { echo "$commit,$date,\"$machine\",$(load),$POINTS,$1,$2,$3,$4,$5" >> "$CSV"; }

laz="$OUT/airborne_$POINTS.laz" las="$OUT/airborne_$POINTS.las"
for r in $(seq 1 "$REPEATS"); do
  g="$("$RUNNER" generate "$POINTS" "$laz" "$las")"
  row pointsurf encode_s "$r" "$(json "$g" encode_s)" s
  [ "$r" = 1 ] && row pointsurf laz_bytes 1 "$(json "$g" laz_bytes)" bytes && row pointsurf las_bytes 1 "$(json "$g" las_bytes)" bytes
  d="$("$RUNNER" decode "$laz")"
  row pointsurf decode_records_s "$r" "$(json "$d" decode_records_s)" s
  row pointsurf read_cloud_s "$r" "$(json "$d" read_cloud_s)" s
  n="$(node "$ROOT/tests/io/lazperf_decode.js" "$LAZPERF" "$laz" -)"
  row laz-perf decode_records_s "$r" "${n#* }" s
done
rm -f "$las"
python3 - "$CSV" "$commit" "$POINTS" <<'PY'
import csv, statistics, sys
rows = [r for r in csv.DictReader(open(sys.argv[1])) if r["commit"] == sys.argv[2] and r["points"] == sys.argv[3]]
def med(tool, measure):
    v = [float(r["value"]) for r in rows if r["tool"] == tool and r["measure"] == measure]
    return statistics.median(v) if v else float("nan")
n = int(sys.argv[3])
ours, theirs = med("pointsurf", "decode_records_s"), med("laz-perf", "decode_records_s")
print(f"points {n}: LAZ {med('pointsurf','laz_bytes')/1e6:.1f} MB, LAS {med('pointsurf','las_bytes')/1e6:.1f} MB, ratio {med('pointsurf','las_bytes')/med('pointsurf','laz_bytes'):.2f}")
print(f"decode records: pointsurf {ours:.3f} s ({n/ours/1e6:.1f} Mpts/s), laz-perf {theirs:.3f} s ({n/theirs/1e6:.1f} Mpts/s), ratio {theirs/ours:.2f}x")
print(f"read into a cloud: pointsurf {med('pointsurf','read_cloud_s'):.3f} s; encode (write LAZ): {med('pointsurf','encode_s'):.3f} s")
PY
