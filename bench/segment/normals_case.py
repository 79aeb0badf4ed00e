#!/usr/bin/python3
# Converts a cloud with normals written by pointsurf (binary PLY, e.g. `pointsurf normals` output)
# into the segment bench's inputs: the scene PLY (truth -1, or the int field TRUTH_FIELD) and the
# raw dump for the C++ peers.
#   normals_case.py IN.ply OUT.ply OUT.bin [TRUTH_FIELD]
import sys

import numpy as np

from b9_outline_picture import read_ply
from scene_io import write_scene

cloud = read_ply(sys.argv[1])
points_normals = np.stack([cloud[k] for k in ("x", "y", "z", "nx", "ny", "nz")], axis=1).astype(np.float64)
truth = cloud[sys.argv[4]].astype(np.int32) if len(sys.argv) > 4 else np.full(len(cloud), -1, np.int32)
write_scene(points_normals, truth, sys.argv[2], sys.argv[3])
