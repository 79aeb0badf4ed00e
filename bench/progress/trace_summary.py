#!/usr/bin/env python3
"""Summarises a POINTSURF_PROGRESS_TRACE file (docs/cli.md, "Progress"): per stage, the number
of progress calls, the longest gap between them (start and end included), the largest
|reported share - elapsed share| (the reported fraction held until the next call, so the error
just before a jump counts), and the time spent in each named phase."""
import sys


def summarise(path):
    stages = {}
    for line in open(path):
        if line.startswith("#") or not line.strip():
            continue
        t, index, stage, event, value = line.rstrip("\n").split("\t")
        s = stages.setdefault((int(index), stage), {"events": [], "end": None})
        if event == "end":
            s["end"] = float(t)
        else:
            s["events"].append((float(t), event, value))
    out = []
    for (index, stage), s in sorted(stages.items()):
        end = s["end"] if s["end"] is not None else (s["events"][-1][0] if s["events"] else 0.0)
        calls = [(t, float(v)) for t, e, v in s["events"] if e == "fraction"]
        times = [0.0] + [t for t, ev, _ in s["events"] if ev != "start"] + [end]
        gap, gap_at = 0.0, 0.0
        for a, b in zip(times, times[1:]):
            if b - a > gap:
                gap, gap_at = b - a, a
        # share error: fraction f holds from its call to the next one
        err, err_at, f = 0.0, 0.0, 0.0
        points = calls + [(end, 1.0)]
        for t, g in points:
            e = abs(f - t / end) if end > 0 else 0.0  # just before the call
            if e > err:
                err, err_at = e, t
            f = max(f, g)
            e = abs(f - t / end) if end > 0 else 0.0  # just after
            if e > err:
                err, err_at = e, t
        monotone = all(b >= a for (_, a), (_, b) in zip(calls, calls[1:]))
        phases, current, since = {}, "(unnamed)", 0.0
        for t, e, v in s["events"]:
            if e == "phase":
                phases[current] = phases.get(current, 0.0) + t - since
                current, since = v, t
        phases[current] = phases.get(current, 0.0) + end - since
        out.append((index, stage, end, len(calls), gap, gap_at, err, err_at, monotone, calls[-1][1] if calls else None, phases))
    return out


def main():
    for path in sys.argv[1:]:
        for index, stage, end, n, gap, gap_at, err, err_at, monotone, last, phases in summarise(path):
            print(f"{path}: stage {index} {stage}: {end:.2f} s, {n} progress calls, max gap {gap:.2f} s (from {gap_at:.2f} s), "
                  f"max |reported - elapsed share| {100 * err:.1f} % (at {err_at:.2f} s), monotone {monotone}, last {last}")
            for name, seconds in phases.items():
                if seconds > 0.0:
                    print(f"    phase {name}: {seconds:.2f} s ({100 * seconds / end if end else 0:.1f} %)")


if __name__ == "__main__":
    main()
