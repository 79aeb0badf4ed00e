#!/usr/bin/env bash
# Curvature (jet fitting) benchmark: pointsurf estimate_curvature next to CGAL's
# Monge_via_jet_fitting on the same inputs, the same k and degree, in the same run.
#   bench/shape/run_shape_bench.sh [SIZES] [REPEATS]     (default: "100000 1000000" 3)
# Clouds above 100k points run LARGE_REPEATS times (default 1: CGAL needs minutes there).
# Inputs: a sphere of radius 1 with exact normals (known curvature: k1 = k2 = H = 1) and the
# armadillo clouds of bench/run_bench.sh (bench/out/armadillo_N.ply, normals from the mesh).
# pointsurf runs with all cores and with 1 thread (CGAL's fitting loop is sequential);
# each configuration REPEATS times, medians reported; peak memory from /usr/bin/time -v.
# Needs BUILD_DIR (default build) with bench/shape_runner built; compiles the CGAL peer.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
SIZES="${1:-100000 1000000}"
REPEATS_SMALL="${2:-3}"
LARGE_REPEATS="${LARGE_REPEATS:-1}"
REPEATS="$REPEATS_SMALL"
OUT="$ROOT/bench/out"
WORK="$OUT/shape"
PY=/usr/bin/python3
RUNNER="${RUNNER:-$BUILD_DIR/bench/shape_runner}"
CGAL_BIN="$WORK/cgal_jet_curvature"
mkdir -p "$WORK"

if [ ! -x "$CGAL_BIN" ] || [ "$ROOT/bench/shape/cgal_jet_curvature.cpp" -nt "$CGAL_BIN" ]; then
  g++ -O2 -std=c++17 -DNDEBUG -DCGAL_EIGEN3_ENABLED -I/usr/include/eigen3 "$ROOT/bench/shape/cgal_jet_curvature.cpp" \
    -o "$CGAL_BIN" -lgmp -lmpfr
fi

peak_mb() { awk '/Maximum resident set size/ {printf "%.1f", $6 / 1024}' "$1"; }

RESULTS="$WORK/results.jsonl"
: > "$RESULTS"
run_case() {  # name cloud k degree
  local name="$1" cloud="$2" k="$3" degree="$4"
  "$RUNNER" dump "$cloud" "$WORK/$name.bin"
  for threads in 0 1; do
    echo "[$name] pointsurf threads=$threads degree=$degree x$REPEATS" >&2
    /usr/bin/time -v -o "$WORK/time.txt" "$RUNNER" curvature "$cloud" "$k" "$degree" "$threads" "$REPEATS" \
      "$WORK/${name}_d${degree}_pointsurf.k" > "$WORK/line.json"
    "$PY" -c 'import json,sys; d=json.load(open(sys.argv[1])); d.update(case=sys.argv[2], peak_mb=float(sys.argv[3])); print(json.dumps(d))' \
      "$WORK/line.json" "$name" "$(peak_mb "$WORK/time.txt")" >> "$RESULTS"
  done
  for ((r = 0; r < REPEATS; r++)); do
    echo "[$name] cgal degree=$degree run $((r + 1))/$REPEATS" >&2
    /usr/bin/time -v -o "$WORK/time.txt" "$CGAL_BIN" "$WORK/$name.bin" "$k" "$degree" "$WORK/${name}_d${degree}_cgal.k" > "$WORK/line.json"
    "$PY" -c 'import json,sys; d=json.load(open(sys.argv[1])); d.update(case=sys.argv[2], peak_mb=float(sys.argv[3])); print(json.dumps(d))' \
      "$WORK/line.json" "$name" "$(peak_mb "$WORK/time.txt")" >> "$RESULTS"
  done
  "$PY" - "$WORK/${name}_d${degree}_pointsurf.k" "$WORK/${name}_d${degree}_cgal.k" "$name" "$degree" >> "$WORK/quality.jsonl" <<'PYEOF'
import json, sys
import numpy as np
ps = np.fromfile(sys.argv[1]).reshape(-1, 2)
cg = np.fromfile(sys.argv[2]).reshape(-1, 2)
name, degree = sys.argv[3], int(sys.argv[4])
out = {"case": name, "degree": degree}
for tool, k in (("pointsurf", ps), ("cgal", cg)):
    h = 0.5 * (k[:, 0] + k[:, 1])
    if name.startswith("sphere"):  # radius 1: H = 1
        e = np.abs(h - 1.0)
        out[tool] = {"H_median_rel_err": float(np.median(e)), "H_p95_rel_err": float(np.quantile(e, 0.95)),
                     "within_2pct": float(np.mean(e <= 0.02))}
hp, hc = 0.5 * ps.sum(1), 0.5 * cg.sum(1)
out["H_diff_median_over_median_abs_H"] = float(np.median(np.abs(hp - hc)) / np.median(np.abs(hc)))
out["H_sign_agreement"] = float(np.mean(np.sign(hp) == np.sign(hc)))
print(json.dumps(out))
PYEOF
}

: > "$WORK/quality.jsonl"
for n in $SIZES; do
  if [ "$n" -gt 100000 ]; then REPEATS="$LARGE_REPEATS"; else REPEATS="$REPEATS_SMALL"; fi
  sphere="$WORK/sphere_${n}.ply"
  [ -f "$sphere" ] || "$RUNNER" sphere "$n" 1.0 "$sphere"
  run_case "sphere_${n}" "$sphere" 24 2
  if [ "$n" -le 100000 ]; then run_case "sphere_${n}" "$sphere" 40 3; fi
  armadillo="$OUT/armadillo_${n}.ply"
  if [ -f "$armadillo" ]; then run_case "armadillo_${n}" "$armadillo" 24 2; else echo "skip: $armadillo missing (run bench/run_bench.sh)" >&2; fi
done

"$PY" - "$RESULTS" "$WORK/quality.jsonl" <<'PYEOF' | tee "$OUT/shape.md"
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
quality = [json.loads(l) for l in open(sys.argv[2]) if l.strip()]
def cases():
    seen = []
    for r in rows:
        key = (r["case"], r["degree"])
        if key not in seen: seen.append(key)
    return seen
def time_of(case, degree, tool, threads):
    t = [r for r in rows if r["case"] == case and r["degree"] == degree and r["tool"] == tool and r["threads"] == threads] \
        if threads else [r for r in rows if r["case"] == case and r["degree"] == degree and r["tool"] == tool and r["threads"] > 1]
    if not t: return None, None, None
    secs, cpu = [], []
    for r in t:
        secs += r["curvature_seconds"] if isinstance(r["curvature_seconds"], list) else [r["curvature_seconds"]]
        cpu += r["curvature_cpu_seconds"] if isinstance(r["curvature_cpu_seconds"], list) else [r["curvature_cpu_seconds"]]
    return (statistics.median(secs), statistics.median(cpu)), max(r["peak_mb"] for r in t), t[0]["threads"]
print("# Curvature benchmark: pointsurf vs CGAL Monge_via_jet_fitting\n")
print("Curvature stage only (kd-tree built before, timed apart), median of the runs, as wall / CPU seconds")
print("(CPU = user + system of all threads, the fairer figure: timing was taken on a shared 2-core machine")
print("under load from other builds). Peak memory of the whole process (reading included).\n")
print("| input | degree, k | CGAL 1 thread | pointsurf 1 thread | ratio wall / CPU | pointsurf all threads | ratio wall | peak MB CGAL / pointsurf |")
print("|---|---|---|---|---|---|---|---|")
for case, degree in cases():
    c, cm, _ = time_of(case, degree, "cgal", 1)
    p1, pm, _ = time_of(case, degree, "pointsurf", 1)
    pa, pam, th = time_of(case, degree, "pointsurf", 0)
    k = next(r["k"] for r in rows if r["case"] == case and r["degree"] == degree)
    fmt = lambda v: "-" if v is None else f"{v[0]:.3f} / {v[1]:.3f} s"
    ratio = lambda a, b, i: "-" if a is None or b is None else f"{a[i] / b[i]:.2f}"
    pam_s = "-" if pam is None else f"{pam:.0f}"
    print(f"| {case} | {degree}, {k} | {fmt(c)} | {fmt(p1)} | {ratio(p1, c, 0)} / {ratio(p1, c, 1)} | {fmt(pa)} ({th} thr) | {ratio(pa, c, 0)} | {cm:.0f} / {pam_s} |")
print("\nratio = pointsurf / CGAL time (below 1: pointsurf faster).\n")
print("| input | degree | tool | median rel. error of H | 95th pct | points within 2 % |")
print("|---|---|---|---|---|---|")
for q in quality:
    for tool in ("pointsurf", "cgal"):
        if tool in q:
            v = q[tool]
            print(f"| {q['case']} | {q['degree']} | {tool} | {100*v['H_median_rel_err']:.3f} % | {100*v['H_p95_rel_err']:.3f} % | {100*v['within_2pct']:.2f} % |")
print("\n| input | degree | median abs(H_pointsurf - H_cgal) / median abs(H_cgal) | same sign of H |")
print("|---|---|---|---|")
for q in quality:
    print(f"| {q['case']} | {q['degree']} | {q['H_diff_median_over_median_abs_H']:.4f} | {100*q['H_sign_agreement']:.2f} % |")
PYEOF
