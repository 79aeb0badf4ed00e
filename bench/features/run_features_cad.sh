#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Feature points on CAD parts (issue 13 item 1): the default detect_feature_points on meshes of
# libcgal-demo, sampled area-uniformly (seed 1), clean and with Gaussian noise, scored per part.
#   bench/features/run_features_cad.sh [POINTS] [NOISES] [REPEATS]
#   (default: 100000 "0 0.1" 1; NOISES: sigma in mean spacings)
# Truth (issue 13): samples within 0.5 mean spacing of a mesh edge (vertices welded by position)
# whose faces turn by at least 30 degrees; a labelled point is right within 1.5 spacings.
# Seconds: detect_feature_points with its kd-tree built inside the timer (median of REPEATS).
# The defaults were tuned on fandisk, anchor and tripod (TUNED below); fandisk_large, pinion and
# spool were looked at to find why points were missed; the other parts were not tuned on.
# Appends raw rows to bench/results/features_cad.csv (commit, date, machine) and writes
# bench/out/features_cad.md. Needs $BUILD_DIR/bench/features_runner and libcgal-demo's data.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD_DIR="${BUILD_DIR:-$ROOT/build}"
POINTS="${1:-100000}"
NOISES="${2:-0 0.1}"
REPEATS="${3:-1}"
RUNNER="$BUILD_DIR/bench/features_runner"
OUT="$ROOT/bench/out"
DATA="$OUT/cgal_meshes"
PY=/usr/bin/python3
# Parts with sharp edges. The last group are thin shells or coarse tessellations of curved
# surfaces, where most 30-degree mesh edges are facets of a smooth surface or both sides of a
# wall lie inside one neighbourhood: reported, not counted in the target.
PARTS="fandisk anchor tripod fandisk_large pinion spool joint part dragknob P cube-meshed cross u star beam cheese-box"
HARD="couplingdown helmet turbine rotor blade"
TUNED="fandisk anchor tripod"
LOOKED="fandisk_large pinion spool"
mkdir -p "$DATA" "$ROOT/bench/results"
[ -x "$RUNNER" ] || { echo "error: $RUNNER not found (build features_runner)" >&2; exit 1; }
if [ ! -f "$DATA/fandisk.off" ]; then
  [ -f /usr/share/doc/libcgal-demo/data.tar.gz ] || { echo "error: needs libcgal-demo's data.tar.gz" >&2; exit 1; }
  tar xzf /usr/share/doc/libcgal-demo/data.tar.gz -C "$DATA" --strip-components=2 data/meshes
fi
ROWS="$OUT/features_cad.jsonl"
: > "$ROWS"
for part in $PARTS $HARD; do
  for noise in $NOISES; do
    echo "[$part] noise $noise" >&2
    "$RUNNER" "$DATA/$part.off" "$POINTS" "$noise" "$REPEATS" | head -1 |
      "$PY" -c 'import json, sys; r = json.load(sys.stdin); r["part"] = sys.argv[1]; print(json.dumps(r))' "$part" >> "$ROWS"
  done
done
"$PY" - "$ROWS" "$ROOT" "$TUNED" "$LOOKED" "$HARD" <<'PYEOF' | tee "$OUT/features_cad.md"
import csv, datetime, json, os, subprocess, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
root, tuned, looked, hard = sys.argv[2], sys.argv[3].split(), sys.argv[4].split(), sys.argv[5].split()
commit = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
machine = f"{os.uname().nodename} {os.cpu_count()} cores"
role = lambda p: "tuned" if p in tuned else "looked at" if p in looked else "hard (not counted)" if p in hard else "unseen"
keys = ["part", "role", "points", "noise_spacings", "precision", "recall", "labelled", "truth", "seconds", "candidates", "threshold",
        "recall_turn_30", "truth_turn_30", "recall_turn_60", "truth_turn_60", "recall_turn_90", "truth_turn_90", "mean_spacing"]
path = os.path.join(root, "bench/results/features_cad.csv")
new = not os.path.exists(path)
with open(path, "a", newline="") as f:
    w = csv.writer(f)
    if new: w.writerow(["commit", "date", "machine"] + keys)
    for r in rows:
        r["role"] = role(r["part"])
        w.writerow([commit, date, machine] + [r.get(k, "") for k in keys])
print(f"# Feature points on CAD parts ({commit}, {date}, {machine})\n")
print("Truth: samples within 0.5 spacing of a mesh edge turning by at least 30 degrees; a label is right within 1.5 spacings.")
print("Target: precision >= 0.95 and recall >= 0.9 with the defaults.\n")
print("| part | role | noise | precision | recall | recall by turn 30-60 / 60-90 / 90-120 deg | labelled / truth | seconds | met |")
print("|---|---|---|---|---|---|---|---|---|")
for r in rows:
    met = "yes" if r["precision"] >= 0.95 and r["recall"] >= 0.9 else "no"
    bins = " / ".join(f"{r[f'recall_turn_{b}']:.2f}" if r[f"truth_turn_{b}"] else "-" for b in (30, 60, 90))
    print(f"| {r['part']} | {r['role']} | {r['noise_spacings']:g} | {r['precision']:.3f} | {r['recall']:.3f} | {bins} | "
          f"{r['labelled']} / {r['truth']} | {r['seconds']:.2f} | {met} |")
counted = [r for r in rows if r["role"] == "unseen"]
print(f"\nUnseen parts meeting the target: {sum(r['precision'] >= 0.95 and r['recall'] >= 0.9 for r in counted)} of {len(counted)} rows.")
PYEOF
