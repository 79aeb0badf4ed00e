#!/usr/bin/python3
# Converts CGAL's demo building.ply (ASCII x y z nx ny nz segment_index; 100k points, its
# segment_index a reference plane labelling) into the runner's inputs: a binary PLY with the
# int field "truth" (-1 unlabelled) and the raw dump for the CGAL peer.
#   building_case.py building.ply OUT.ply OUT.bin
import sys
import numpy as np

from scene_io import write_scene

src, out_ply, out_bin = sys.argv[1:4]
with open(src) as f:
    skip = 0
    for line in f:
        skip += 1
        if line.startswith("end_header"):
            break
d = np.loadtxt(src, skiprows=skip)
write_scene(d[:, :6], d[:, 6].astype(np.int32), out_ply, out_bin)
