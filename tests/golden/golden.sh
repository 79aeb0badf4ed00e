#!/usr/bin/env bash
# Golden set of issue 27: runs tests/golden/commands.txt with a pointsurf binary, --threads 1,
# and writes OUTDIR/manifest.txt: a SHA-256 per output file and per report (reports with
# timings, memory, kd-tree counts and the version removed).
#   tests/golden/golden.sh record CLI OUTDIR      run and write the manifest
#   tests/golden/golden.sh compare BASE NEW       compare two recorded folders, file by file
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
mode="${1:-}"
if [ "$mode" = record ]; then
  CLI="$(realpath "$2")"; O="$(realpath -m "$3")"
  rm -rf "$O"; mkdir -p "$O/reports"
  cd "$ROOT"
  n=0
  while IFS= read -r line; do
    case "$line" in ''|'#'*) continue ;; esac
    n=$((n + 1))
    cmd="${line//\$O/$O}"
    read -r -a words <<<"$cmd"
    report="$O/reports/$(printf '%02d' $n)_${words[0]}.json"
    if [ "${words[0]}" = run ]; then
      # Pipelines write under out/: run them in a scratch copy so out/ of the checkout stays as it is.
      scratch="$O/run$n"; mkdir -p "$scratch/out"; ln -s "$ROOT/data" "$scratch/data"; ln -s "$ROOT/examples" "$scratch/examples"
      (cd "$scratch" && "$CLI" "${words[@]}" --threads 1 --quiet --report "$report") >"$O/reports/$(printf '%02d' $n).log" 2>&1
    else
      "$CLI" "${words[@]}" --threads 1 --quiet --report "$report" >"$O/reports/$(printf '%02d' $n).log" 2>&1
    fi
    echo "$n rc=$? $line" >>"$O/status.txt"
  done <"$ROOT/tests/golden/commands.txt"
  # Reports without what changes from run to run.
  for r in "$O"/reports/*.json "$O"/*.json; do
    [ -f "$r" ] || continue
    /usr/bin/python3 - "$r" "$O" <<'PY'
import json, sys
path, out = sys.argv[1], sys.argv[2]
DROP = {"seconds", "peak_rss_mb", "rss_rise_mb", "tree_builds", "version", "date", "started", "finished", "elapsed_seconds",
        "wall_seconds", "cpu_seconds", "threads", "hostname", "command_line", "argv", "total_seconds"}
def clean(x):
    if isinstance(x, dict):
        return {k: clean(v) for k, v in x.items() if k not in DROP and "seconds" not in k}
    if isinstance(x, list):
        return [clean(v) for v in x]
    if isinstance(x, str):
        return x.replace(out, "$O")
    return x
with open(path) as f:
    data = json.load(f)
with open(path + ".clean", "w") as f:
    json.dump(clean(data), f, indent=1, sort_keys=True)
PY
  done
  (cd "$O" && find . -type f ! -name '*.log' ! -name 'manifest.txt' ! -path './reports/*.json' ! -path './*.json' -printf '%P\n' | sort |
     while read -r f; do printf '%s  %s\n' "$(sha256sum "$f" | cut -c1-64)" "$f"; done) >"$O/manifest.txt"
  echo "golden: $n commands, $(grep -vc ' rc=0 ' "$O/status.txt") failed; manifest $O/manifest.txt" >&2
elif [ "$mode" = compare ]; then
  A="$2"; B="$3"
  diff <(sed 's/ rc=/ rc=/' "$A/status.txt") "$B/status.txt" >/dev/null || { echo "status differs:"; diff "$A/status.txt" "$B/status.txt"; }
  join -j 2 <(awk '{print $1, $2}' "$A/manifest.txt" | sort -k2) <(awk '{print $1, $2}' "$B/manifest.txt" | sort -k2) -a1 -a2 -e MISSING -o 0,1.1,2.1 |
    awk '$2 != $3 {print "differs: " $1; bad=1} END {exit bad}'
  rc=$?
  [ $rc -eq 0 ] && echo "golden: identical ($(wc -l <"$A/manifest.txt") files)"
  exit $rc
else
  sed -n '2,7p' "$0" | sed 's/^# \{0,1\}//'; exit 1
fi
