#!/usr/bin/env bash
# Cleaning benchmark: pointsurf next to Open3D (statistical and radius outlier removal, same
# input, same run, kept sets compared point by point) and CGAL (bilateral_smooth_point_set,
# time and distance to the true surface), plus pointsurf's own quality figures.
#   bench/clean/run_clean_bench.sh [SIZES] [REPEATS]      (default: "100000 1000000" 3)
# Needs $BUILD_DIR/bench/clean_runner and pointsurf_bench (-DPOINTSURF_BUILD_BENCHMARKS=ON),
# python3-open3d under /usr/bin/python3, libcgal-dev. Writes bench/out/clean.md.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
SIZES="${1:-100000 1000000}"
REPEATS="${2:-3}"
SMOOTH_POINTS="${SMOOTH_POINTS:-100000}"
RUNNER="$BUILD_DIR/bench/clean_runner"
OUT="$ROOT/bench/out"
WORK="$OUT/clean"
PY=/usr/bin/python3
mkdir -p "$WORK"
RESULTS="$WORK/results.jsonl"
: > "$RESULTS"

# Inputs: the armadillo sampled at each size, as in bench/run_bench.sh.
MESH=armadillo
if [ ! -f "$OUT/$MESH.off" ]; then
  tar xzf /usr/share/doc/libcgal-demo/data.tar.gz -C "$OUT" "data/meshes/$MESH.off"
  mv "$OUT/data/meshes/$MESH.off" "$OUT/$MESH.off"
  rm -rf "$OUT/data"
fi

peak() { awk -F': ' '/Maximum resident/ {printf "%.1f", $2 / 1024}' "$1"; }
for n in $SIZES; do
  cloud="$OUT/${MESH}_${n}.ply"
  [ -f "$cloud" ] || "$BUILD_DIR/bench/pointsurf_bench" sample "$OUT/$MESH.off" "$n" "$cloud" 1
  spacing=$("$RUNNER" spacing "$cloud" | $PY -c 'import json,sys; print(json.load(sys.stdin)["spacing"])')
  radius=$($PY -c "print(4.0 * $spacing)")
  for ((r = 0; r < REPEATS; r++)); do
    for stage in sor radius; do
      if [ "$stage" = sor ]; then a=20; b=2.0; else a=4; b=$radius; fi
      echo "[$n] $stage run $((r + 1))/$REPEATS" >&2
      /usr/bin/time -v "$RUNNER" "$stage" "$cloud" "$a" "$b" "$WORK/kept_pointsurf.txt" > "$WORK/row.json" 2> "$WORK/time.txt"
      $PY -c "import json,sys; r=json.load(open('$WORK/row.json')); r['process_peak_rss_mb']=float('$(peak "$WORK/time.txt")'); print(json.dumps(r))" >> "$RESULTS"
      /usr/bin/time -v "$PY" "$ROOT/bench/clean/open3d_clean.py" "$stage" "$cloud" "$a" "$b" "$WORK/kept_open3d.txt" > "$WORK/row.json" 2> "$WORK/time.txt"
      $PY -c "import json,sys; r=json.load(open('$WORK/row.json')); r['process_peak_rss_mb']=float('$(peak "$WORK/time.txt")'); print(json.dumps(r))" >> "$RESULTS"
      $PY - "$WORK/kept_pointsurf.txt" "$WORK/kept_open3d.txt" "$stage" "$n" >> "$RESULTS" <<'PYEOF'
import json, sys
a = set(int(x) for x in open(sys.argv[1]) if x.strip())
b = set(int(x) for x in open(sys.argv[2]) if x.strip())
print(json.dumps({"tool": "compare", "stage": sys.argv[3], "points": int(sys.argv[4]), "differing": len(a ^ b)}))
PYEOF
    done
  done
done

# Bilateral against CGAL on noisy synthetic shapes with known surfaces (noise 0.5 spacing).
CGAL_BIN="$WORK/cgal_bilateral"
if [ ! -x "$CGAL_BIN" ] || [ "$ROOT/bench/clean/cgal_bilateral.cpp" -nt "$CGAL_BIN" ]; then
  echo "compiling cgal_bilateral" >&2
  g++ -O2 -std=c++17 -DNDEBUG -DCGAL_LINKED_WITH_TBB -I/usr/include/eigen3 "$ROOT/bench/clean/cgal_bilateral.cpp" -o "$CGAL_BIN" \
    -ltbb -lgmp -lmpfr -lpthread
fi
for shape in sphere cube part; do
  noisy="$WORK/${shape}_${SMOOTH_POINTS}_noisy.ply"
  "$RUNNER" synth "$shape" "$SMOOTH_POINTS" 0.5 "$noisy" 1 > /dev/null
  "$RUNNER" score "$shape" "$noisy" | $PY -c "import json,sys; r=json.load(sys.stdin); r.update(tool='input', shape='$shape'); print(json.dumps(r))" >> "$RESULTS"
  for ((r = 0; r < REPEATS; r++)); do
    for tool in bilateral trilateral cgal; do
      echo "[$shape] $tool run $((r + 1))/$REPEATS" >&2
      out="$WORK/${shape}_${tool}.ply"
      if [ "$tool" = cgal ]; then
        /usr/bin/time -v "$CGAL_BIN" "$noisy" "$out" 24 25 2 > "$WORK/row.json" 2> "$WORK/time.txt"
      else
        /usr/bin/time -v "$RUNNER" smooth "$tool" "$noisy" "$out" > "$WORK/row.json" 2> "$WORK/time.txt"
      fi
      "$RUNNER" score "$shape" "$out" > "$WORK/score.json"
      $PY -c "import json; r=json.load(open('$WORK/row.json')); r.update(json.load(open('$WORK/score.json'))); r.update(shape='$shape', method='$tool', process_peak_rss_mb=float('$(peak "$WORK/time.txt")')); print(json.dumps(r))" >> "$RESULTS"
    done
  done
done

echo "[quality] outliers and smoothing on sphere, cube, part" >&2
"$RUNNER" quality >> "$RESULTS"

$PY - "$RESULTS" "$SIZES" "$REPEATS" "$SMOOTH_POINTS" <<'PYEOF' | tee "$OUT/clean.md"
import json, os, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
repeats = sys.argv[3]
def med(filt, key):
    v = [r[key] for r in rows if filt(r) and key in r]
    return statistics.median(v) if v else float("nan")
print("# Cleaning benchmark\n")
print(f"Command: `bench/clean/run_clean_bench.sh \"{sys.argv[2]}\" {repeats}` (medians of {repeats} runs; {os.cpu_count()} cores,")
print("timings taken on a shared machine under load from other builds, so treat ratios as indicative).\n")
print("## Outlier removal against Open3D 0.16 (armadillo samples; time includes the kd-tree, excludes reading)\n")
print("| stage | points | pointsurf s | Open3D s | time ratio | pointsurf MiB | Open3D MiB | kept (pointsurf / Open3D) | differing points |")
print("|---|---|---|---|---|---|---|---|---|")
for stage, params in (("sor", "k 20, std ratio 2"), ("radius", "4 neighbours within 4 spacings")):
    for n in sorted({r["points"] for r in rows if r.get("stage") == stage and r.get("tool") == "pointsurf"}):
        f = lambda tool: (lambda r: r.get("tool") == tool and r.get("stage") == stage and r.get("points") == n)
        ps, o3 = med(f("pointsurf"), "seconds"), med(f("open3d"), "seconds")
        print(f"| {stage} ({params}) | {n} | {ps:.3f} | {o3:.3f} | {ps / o3:.2f} | {med(f('pointsurf'), 'process_peak_rss_mb'):.0f} | "
              f"{med(f('open3d'), 'process_peak_rss_mb'):.0f} | {med(f('pointsurf'), 'kept'):.0f} / {med(f('open3d'), 'kept'):.0f} | "
              f"{max(r['differing'] for r in rows if f('compare')(r))} |")
print(f"\n## Bilateral smoothing against CGAL 5.5 bilateral_smooth_point_set ({sys.argv[4]} points, noise 0.5 spacing, PCA normals)\n")
print("RMS distance to the true surface (cloud units; smaller is better): all points, points within 2 spacings of a crease,")
print("flat points farther than 5 spacings. CGAL: k 24, sharpness 25 deg, 2 iterations; pointsurf defaults (radius 3 spacings, 2 iterations).\n")
print("| shape | method | seconds | peak MiB | RMS all | RMS near creases | RMS flat |")
print("|---|---|---|---|---|---|---|")
for shape in ("sphere", "cube", "part"):
    inp = [r for r in rows if r.get("tool") == "input" and r.get("shape") == shape]
    if inp:
        r = inp[0]
        print(f"| {shape} | noisy input | - | - | {r['rms_all']:.5f} | {r.get('rms_edge', float('nan')):.5f} | {r.get('rms_flat', float('nan')):.5f} |")
    for m in ("bilateral", "trilateral", "cgal"):
        f = lambda r: r.get("shape") == shape and r.get("method") == m
        name = {"bilateral": "pointsurf bilateral", "trilateral": "pointsurf trilateral", "cgal": "CGAL bilateral"}[m]
        print(f"| {shape} | {name} | {med(f, 'seconds'):.2f} | {med(f, 'process_peak_rss_mb'):.0f} | {med(f, 'rms_all'):.5f} | "
              f"{med(f, 'rms_edge'):.5f} | {med(f, 'rms_flat'):.5f} |")
print("\n## Quality on synthetic shapes (100k points, noise 0.5 spacing, seeded)\n")
print("Outlier removal with default parameters; 0.5% drift points (3..15 spacings above the surface) and 0.5% scattered points.\n")
print("| shape | points | outliers | SOR precision / recall | radius precision / recall | RANSAC precision / recall |")
print("|---|---|---|---|---|---|")
for r in rows:
    if r.get("stage") == "outlier_quality":
        q = r["result"]
        cell = lambda m: f"{q[m]['precision']:.3f} / {q[m]['recall']:.3f}"
        print(f"| {q['shape']} | {q['points']} | {q['outliers']} | {cell('sor')} | {cell('radius')} | {cell('ransac')} |")
print("\nDenoising (defaults), RMS distance to the true surface before -> after:\n")
print("| shape | spacing | before all | bilateral all / creases / flat | trilateral all / creases / flat | bilateral s | trilateral s |")
print("|---|---|---|---|---|---|---|")
for r in rows:
    if r.get("stage") == "smooth_quality":
        q = r["result"]
        t = lambda m: f"{q[m]['rms_all']:.5f} / {q[m].get('rms_edge', float('nan')):.5f} / {q[m].get('rms_flat', float('nan')):.5f}"
        print(f"| {q['shape']} | {q['spacing']:.5f} | {q['before']['rms_all']:.5f} (creases {q['before'].get('rms_edge', float('nan')):.5f}) | "
              f"{t('bilateral')} | {t('trilateral')} | {q['bilateral']['seconds']:.2f} | {q['trilateral']['seconds']:.2f} |")
PYEOF
