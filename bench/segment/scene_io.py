# Writes a labelled oriented cloud for the segment bench: a binary PLY (x y z nx ny nz double,
# int truth) for pointsurf and Open3D, and a raw dump (uint64 N, N x 6 float64) for the CGAL peer.
import numpy as np


def write_scene(points_normals, truth, out_ply, out_bin):
    rec = np.zeros(len(points_normals), dtype=[("p", "<f8", 6), ("truth", "<i4")])
    rec["p"] = points_normals
    rec["truth"] = truth
    with open(out_ply, "wb") as f:
        f.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\n" % len(rec)).encode())
        for k in "x y z nx ny nz".split():
            f.write(("property double %s\n" % k).encode())
        f.write(b"property int truth\nend_header\n")
        f.write(rec.tobytes())
    with open(out_bin, "wb") as f:
        f.write(np.uint64(len(rec)).tobytes())
        f.write(np.ascontiguousarray(points_normals, dtype="<f8").tobytes())


def truth_of(path):
    """The int field "truth" of a scene PLY written by write_scene."""
    with open(path, "rb") as f:
        head = b""
        while not head.endswith(b"end_header\n"):
            head += f.readline()
        n = int([l for l in head.split(b"\n") if l.startswith(b"element vertex")][0].split()[2])
        rec = np.frombuffer(f.read(), dtype=[("p", "<f8", 6), ("truth", "<i4")], count=n)
    return rec["truth"]
