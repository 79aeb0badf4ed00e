#!/usr/bin/python3
# Agreement of two labellings (int32 files, -1 unassigned), and of the first with the scene's
# truth when it has one. Prints JSON:
#   ari: adjusted Rand index (Hubert, Arabie 1985) over the points both labellings assign;
#   both_assigned: the share of points that both assign;
#   iou_a_in_b: mean over A's segments, weighted by size, of the best IoU with a segment of B
#       (unassigned points count against the IoU);
#   truth_*: the same of A against the truth (points of truth -1 left out), and truth_iou: per
#       truth segment, its best IoU with a segment of A.
#   agreement.py LABELS_A LABELS_B [SCENE.ply]
import json
import sys

import numpy as np

from scene_io import truth_of


def ari(a, b):
    """Adjusted Rand index of two labellings of the same points (no -1)."""
    def pairs(counts):
        counts = counts.astype(np.float64)
        return float((counts * (counts - 1) / 2).sum())
    _, joint = np.unique(np.stack([a, b]), axis=1, return_counts=True)
    sum_ij = pairs(joint)
    sum_a = pairs(np.unique(a, return_counts=True)[1])
    sum_b = pairs(np.unique(b, return_counts=True)[1])
    expected = sum_a * sum_b / pairs(np.array([len(a)]))
    top = 0.5 * (sum_a + sum_b)
    return 1.0 if top == expected else (sum_ij - expected) / (top - expected)


def best_iou(a, b):
    """Per segment of a (ids >= 0, ascending): its size and its best IoU with a segment of b."""
    ids = np.unique(a[a >= 0])
    size_b = np.bincount(b[b >= 0], minlength=1)
    out = []
    for s in ids:
        inside = b[a == s]
        inside = inside[inside >= 0]
        n = int((a == s).sum())
        if len(inside) == 0:
            out.append((n, 0.0))
            continue
        hits = np.bincount(inside)
        t = int(hits.argmax())
        out.append((n, float(hits[t]) / float(n + size_b[t] - hits[t])))
    return out


def compare(a, b):
    both = (a >= 0) & (b >= 0)
    per = best_iou(a, b)
    weighted = sum(n * iou for n, iou in per) / max(sum(n for n, _ in per), 1)
    return {"ari": round(ari(a[both], b[both]), 4), "both_assigned": round(float(both.mean()), 4), "iou_a_in_b": round(weighted, 4)}


def main():
    a = np.fromfile(sys.argv[1], dtype=np.int32)
    b = np.fromfile(sys.argv[2], dtype=np.int32)
    out = compare(a, b)
    if len(sys.argv) > 3:
        truth = truth_of(sys.argv[3])
        keep = truth >= 0
        if keep.any():
            t = compare(truth[keep], a[keep])
            out.update({"truth_ari": t["ari"], "truth_both_assigned": t["both_assigned"], "truth_iou_weighted": t["iou_a_in_b"],
                        "truth_iou": [round(iou, 4) for _, iou in best_iou(truth[keep], a[keep])]})
    print(json.dumps(out))


if __name__ == "__main__":
    main()
