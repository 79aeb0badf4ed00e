# SPDX-License-Identifier: GPL-3.0-or-later
"""Provenance and CSV rows shared by the sweep scripts (bench/clean/outlier_sweep.sh,
bench/reconstruct/genus_sweep.sh): the commit (+dirty when tracked files changed), the UTC date
and the machine, written before each row's keys."""
import csv
import datetime
import os
import subprocess


def provenance(root):
    """(commit, date, machine) of a run from the repository at `root`."""
    git = lambda *args: subprocess.run(["git", "-C", root, *args], capture_output=True, text=True).stdout.strip()
    commit = git("rev-parse", "--short", "HEAD")
    if git("status", "--porcelain", "--untracked-files=no"):
        commit += "+dirty"
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    return commit, date, f"{os.uname().nodename} {os.cpu_count()} cores"


def append_rows(path, keys, rows, run):
    """Appends `rows` (dicts) to the CSV at `path` as run's provenance + keys, with a header when new."""
    new = not os.path.exists(path)
    with open(path, "a", newline="") as f:
        w = csv.writer(f)
        if new:
            w.writerow(["commit", "date", "machine"] + keys)
        for r in rows:
            w.writerow(list(run) + [r[k] for k in keys])
