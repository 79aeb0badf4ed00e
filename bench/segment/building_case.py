#!/usr/bin/python3
# Converts CGAL's demo building.ply (ASCII x y z nx ny nz segment_index; 100k points, its
# segment_index a reference plane labelling) into the runner's inputs: a binary PLY with the
# int field "truth" (-1 unlabelled) and the raw dump for the CGAL peer.
#   building_case.py building.ply OUT.ply OUT.bin
import sys
import numpy as np

src, out_ply, out_bin = sys.argv[1:4]
with open(src) as f:
    skip = 0
    for line in f:
        skip += 1
        if line.startswith("end_header"):
            break
d = np.loadtxt(src, skiprows=skip)
rec = np.zeros(len(d), dtype=[("p", "<f8", 6), ("truth", "<i4")])
rec["p"] = d[:, :6]
rec["truth"] = d[:, 6].astype(np.int32)
with open(out_ply, "wb") as f:
    f.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\n" % len(d)).encode())
    for k in "x y z nx ny nz".split():
        f.write(("property double %s\n" % k).encode())
    f.write(b"property int truth\nend_header\n")
    f.write(rec.tobytes())
with open(out_bin, "wb") as f:
    f.write(np.uint64(len(d)).tobytes())
    f.write(d[:, :6].astype("<f8").tobytes())
