#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Topological noise (issue 28 item 7): libcgal-demo meshes sampled as in
# bench/clean/outlier_sweep.sh (POINTS points, Gaussian noise of sigma = 0.1 % of the diagonal
# along the normal, 1 % outliers in the grown bounding box), cleaned with `pointsurf clean`'s
# defaults, then `pointsurf reconstruct --method METHOD` (default poisson) with its defaults:
# the genus summed over the components before and after the short-handle cut (max_handle_loop
# 10 cloud spacings), the true genus of the mesh sampled, handles cut, shortest loop, seconds.
#   bench/reconstruct/genus_sweep.sh [POINTS] [SEEDS] [SHAPES] [METHOD]
#   (default: 200000 "1 2 3 4 5" "elephant bull camel cow dino fandisk anchor joint couplingdown
#   3torus double-torus-example" poisson; RECON_ARGS adds options to every reconstruct run)
# Appends rows to bench/results/genus-2026-12-06.csv (commit, date, machine) unless NO_CSV=1;
# writes bench/out/genus.md. Needs $BUILD_DIR/pointsurf, $BUILD_DIR/bench/clean_runner
# (-DPOINTSURF_BUILD_BENCHMARKS=ON) and libcgal-demo's data.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
POINTS="${1:-200000}"
SEEDS="${2:-1 2 3 4 5}"
SHAPES="${3:-elephant bull camel cow dino fandisk anchor joint couplingdown 3torus double-torus-example}"
METHOD="${4:-poisson}"
RUNNER="${RUNNER:-$BUILD_DIR/bench/clean_runner}"
CLI="$BUILD_DIR/pointsurf"
OUT="$ROOT/bench/out"
WORK="$OUT/genus"
DATA="${DATA:-$OUT/cgal_meshes}"
PY=/usr/bin/python3
CSV="$ROOT/bench/results/genus-2026-12-06.csv"
mkdir -p "$WORK" "$DATA"
for tool in "$RUNNER" "$CLI"; do [ -x "$tool" ] || { echo "error: $tool not found" >&2; exit 1; }; done
if [ ! -f "$DATA/fandisk.off" ]; then
  [ -f /usr/share/doc/libcgal-demo/data.tar.gz ] || { echo "error: needs libcgal-demo's data.tar.gz" >&2; exit 1; }
  tar xzf /usr/share/doc/libcgal-demo/data.tar.gz -C "$DATA" --strip-components=2 data/meshes
fi
ROWS="$WORK/rows.jsonl"
: > "$ROWS"
for shape in $SHAPES; do
  "$CLI" info "$DATA/$shape.off" --report "$WORK/truth.json" > /dev/null 2>&1 || true
  for seed in $SEEDS; do
    scan="$WORK/${shape}_$seed.ply"
    "$RUNNER" outliers "$DATA/$shape.off" "$POINTS" "$seed" "$scan" > "$WORK/scan.json"
    "$CLI" clean "$scan" "$WORK/cleaned.ply" > /dev/null 2>&1
    start=$(date +%s.%N)
    "$CLI" reconstruct "$WORK/cleaned.ply" "$WORK/mesh.ply" --method "$METHOD" ${RECON_ARGS:-} --report "$WORK/report.json" > /dev/null 2>&1
    seconds=$(echo "$(date +%s.%N) - $start" | bc)
    "$PY" - "$WORK/report.json" "$DATA/$shape.off" "$shape" "$seed" "$METHOD" "$seconds" "${RECON_ARGS:-}" >> "$ROWS" <<'PYEOF'
import json, sys
report = json.load(open(sys.argv[1]))
r = next(s for s in report["stages"] if s["type"] == "reconstruct")
m, c = r["metrics"], r["counts"]
# The true genus of the mesh sampled: V - E + F of the OFF file (closed, one component assumed).
lines = [l for l in open(sys.argv[2]) if l.strip() and not l.startswith("#")]
head = lines[0].split()
nv, nf = (int(head[1]), int(head[2])) if head[0] == "OFF" and len(head) > 1 else tuple(int(x) for x in lines[1].split()[:2])
start = 1 if len(head) > 1 else 2
edges = set()
for l in lines[start + nv:start + nv + nf]:
    idx = [int(x) for x in l.split()[1:1 + int(l.split()[0])]]
    for i in range(len(idx)):
        a, b = idx[i], idx[(i + 1) % len(idx)]
        edges.add((min(a, b), max(a, b)))
true_genus = (2 - (nv - len(edges) + nf)) // 2
print(json.dumps(dict(shape=sys.argv[3], seed=int(sys.argv[4]), method=sys.argv[5], seconds=float(sys.argv[6]), args=sys.argv[7],
                      true_genus=true_genus, handles_before=m.get("handles_before"), handles_after=m.get("handles"),
                      short_handles=c.get("short_handles", 0), handles_removed=c.get("handles_removed", 0),
                      shortest_loop=m.get("shortest_handle_loop"), limit=m.get("max_handle_loop_length"),
                      components=c.get("components"), triangles=c.get("triangles"))))
PYEOF
    echo "[$shape seed $seed] $(tail -1 "$ROWS")" >&2
  done
done
"$PY" - "$ROWS" "$ROOT" "$POINTS" "$CSV" "${NO_CSV:-0}" <<'PYEOF' | tee "$OUT/genus.md"
import json, os, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
root, points, path, no_csv = sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5] == "1"
sys.path.insert(0, os.path.join(root, "bench"))
from sweep_csv import append_rows, provenance
commit, date, machine = provenance(root)
keys = ["shape", "seed", "method", "args", "true_genus", "handles_before", "handles_after", "short_handles", "handles_removed",
        "shortest_loop", "limit", "components", "triangles", "seconds"]
if not no_csv:
    append_rows(path, keys, rows, (commit, date, machine))
print(f"# Genus after reconstruct, before and after the short-handle cut ({commit}, {date}, {machine}; {points} points + 1 % outliers, cleaned)\n")
print("| shape | method | true genus | seeds | handles before (per seed) | after (per seed) | cut | seconds (mean) |")
print("|---|---|---|---|---|---|---|---|")
groups = []
for r in rows:
    if (r["shape"], r["method"]) not in groups: groups.append((r["shape"], r["method"]))
for shape, method in groups:
    g = [r for r in rows if (r["shape"], r["method"]) == (shape, method)]
    fmt = lambda k: " ".join("-" if r[k] is None else str(r[k]) for r in g)
    print(f"| {shape} | {method} | {g[0]['true_genus']} | {len(g)} | {fmt('handles_before')} | {fmt('handles_after')} | "
          f"{sum(r['handles_removed'] for r in g)} | {sum(r['seconds'] for r in g) / len(g):.2f} |")
PYEOF
