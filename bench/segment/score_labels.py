#!/usr/bin/python3
# Completeness of a labelling against the scene's truth: per truth primitive, the share of its
# points in its most common label (unassigned excluded); prints JSON.
#   score_labels.py SCENE.ply LABELS [TRUTHS]   (TRUTHS: truth ids to score, e.g. 0,1, or big500:
#   those of >= 500 points; default all ids >= 0)
import json, sys
import numpy as np

from scene_io import truth_of

truth = truth_of(sys.argv[1])
labels = np.fromfile(sys.argv[2], dtype=np.int32)
if len(sys.argv) > 3 and sys.argv[3] == "big500":
    ids = [int(k) for k in np.where(np.bincount(truth[truth >= 0]) >= 500)[0]]
elif len(sys.argv) > 3:
    ids = [int(x) for x in sys.argv[3].split(",")]
else:
    ids = sorted(t for t in set(truth.tolist()) if t >= 0)
shares = []
for t in ids:
    l = labels[truth == t]
    l = l[l >= 0]
    shares.append(float(np.bincount(l).max()) / float((truth == t).sum()) if len(l) else 0.0)
print(json.dumps({"shares": [round(s, 4) for s in shares], "recovered_95": sum(s >= 0.95 for s in shares), "recovered_90": sum(s >= 0.9 for s in shares),
                  "of": len(ids)}))
