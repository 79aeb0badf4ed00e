#!/bin/bash
# E57 read/write speed on a seeded 1M-point cloud (colours, intensity) against binary PLY and
# LAS of the same cloud, interleaved in one run, median of 5 (bench/io/e57_runner.cpp). Rows go
# to bench/results/io_e57.csv with commit, date, machine and load.
# Usage: bench/io/e57_bench.sh [build dir=build] [points=1000000]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD="${1:-$ROOT/build}"
POINTS="${2:-1000000}"
RESULTS="$ROOT/bench/results/io_e57.csv"
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT
COMMIT="$(git -C "$ROOT" rev-parse --short HEAD)"
DATE="$(date -u +%Y-%m-%dT%H:%M:%SZ)"
MACHINE="$(nproc) cores $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs | tr ',' ' ')"
LOAD="$(cut -d' ' -f1 /proc/loadavg)"
[ -f "$RESULTS" ] || echo "commit,date,machine,load,format,points,bytes,write_s,read_s,read_mpts_s" > "$RESULTS"
"$BUILD/bench/e57_runner" "$POINTS" 5 "$TMP" | tail -n +2 | while IFS= read -r row; do
  echo "$COMMIT,$DATE,$MACHINE,$LOAD,$row" | tee -a "$RESULTS"
done
