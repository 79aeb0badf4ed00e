#!/usr/bin/python3
"""Colours a segmented cloud by segment (a categorical palette; -1 grey) and adds the outlines
of a GeoJSON file as black points every `step` cloud units, for `pointsurf render`.

usage: b9_outline_picture.py SEGMENTS.ply OUTLINES.geojson OUT.ply [step]
The input PLY is pointsurf's binary little-endian output with the int field `segment`."""
import colorsys
import json
import sys

import numpy as np

TYPES = {"double": "<f8", "float": "<f4", "uchar": "u1", "int": "<i4", "uint": "<u4", "short": "<i2", "ushort": "<u2", "char": "i1"}


def read_ply(path):
    with open(path, "rb") as f:
        fields, n = [], 0
        while (line := f.readline().decode().strip()) != "end_header":
            words = line.split()
            if words[:2] == ["element", "vertex"]:
                n = int(words[2])
            elif words[0] == "property":
                fields.append((words[2], TYPES[words[1]]))
        return np.frombuffer(f.read(n * np.dtype(fields).itemsize), dtype=np.dtype(fields), count=n)


def feature_rings(feature):
    """The lines of a GeoJSON feature as arrays (M x 3): a Polygon's outer ring, then its holes
    (each ring ends at its first point); a LineString as one."""
    geometry = feature["geometry"]
    if geometry["type"] == "Polygon":
        return [np.array(ring, dtype=float) for ring in geometry["coordinates"]]
    return [np.array(geometry["coordinates"], dtype=float)]


def outline_points(features, step, lift=1.0):
    """The outlines of GeoJSON features as points every `step`, lifted `lift` so that a top view
    shows them above the cloud (N x 3)."""
    lines = []
    for c in (ring for feature in features for ring in feature_rings(feature)):
        for a, b in zip(c[:-1], c[1:]):
            k = max(int(np.linalg.norm(b - a) / step), 1)
            lines.append(a + (b - a) * np.linspace(0.0, 1.0, k, endpoint=False)[:, None])
    return np.concatenate(lines) + [0.0, 0.0, lift] if lines else np.zeros((0, 3))


def write_picture(path, xyz, rgb, value):
    """A binary PLY of points with colours and the int field `segment` (`value`) for `pointsurf render`."""
    out = np.zeros(len(xyz), dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("red", "u1"), ("green", "u1"), ("blue", "u1"), ("segment", "<i4")])
    out["x"], out["y"], out["z"] = xyz[:, 0], xyz[:, 1], xyz[:, 2]
    out["red"], out["green"], out["blue"] = rgb[:, 0], rgb[:, 1], rgb[:, 2]
    out["segment"] = value
    header = ["ply", "format binary_little_endian 1.0", f"element vertex {len(out)}"]
    header += [f"property {t} {name}" for name, t in [("x", "double"), ("y", "double"), ("z", "double"), ("red", "uchar"), ("green", "uchar"), ("blue", "uchar"), ("segment", "int")]]
    with open(path, "wb") as f:
        f.write(("\n".join(header + ["end_header"]) + "\n").encode())
        f.write(out.tobytes())


def main():
    cloud = read_ply(sys.argv[1])
    outlines = json.load(open(sys.argv[2]))["features"]
    step = float(sys.argv[4]) if len(sys.argv) > 4 else 0.1
    seg = cloud["segment"]
    xyz = np.stack([cloud["x"], cloud["y"], cloud["z"]], axis=1)
    # Golden-ratio hues: neighbouring segment numbers get distant colours.
    palette = np.array([colorsys.hsv_to_rgb((0.618034 * i) % 1.0, 0.55, 0.95) for i in range(max(seg.max() + 1, 1))]) * 255
    rgb = np.where(seg[:, None] >= 0, palette[np.maximum(seg, 0)], 150).astype(np.uint8)
    line_xyz = outline_points(outlines, step)
    write_picture(sys.argv[3], np.concatenate([xyz, line_xyz]), np.concatenate([rgb, np.zeros((len(line_xyz), 3), np.uint8)]),
                  np.concatenate([seg, np.full(len(line_xyz), -2, np.int32)]))
    print(f"{len(xyz)} points, {len(outlines)} outlines as {len(line_xyz)} points")


if __name__ == "__main__":
    main()
