#!/usr/bin/python3
"""Scores building footprints on the demo's aerial b9 tile against its training strokes, and
writes a picture cloud (strokes coloured by class, footprint outlines in black).

b9_training.ply's int field `label` is CGAL's classification training set (examples/
Classification/example_ethz_random_forest.cpp: 0 ground, 1 vegetation, 2 roof; -1 not stroked,
89 % of the points). The strokes are no full truth: they say nothing about the unstroked points,
so only figures on the stroked points are given:
  roof recall      share of roof-stroke points whose (x, y) lies inside a footprint
  ground / vegetation inside  share of those strokes inside a footprint (false alarms)
  precision        roof strokes inside / all strokes inside (depends on how much of each class
                   was stroked)
  IoU on strokes   roof inside / (roof + ground inside + vegetation inside)
Footprints: the outlines (GeoJSON of `pointsurf boundary --outlines`) of the planar segments
whose median height is at least MIN_HEIGHT above the ground, the median z of segment 0 (the
largest plane); a point is inside a segment's footprint when it is inside one of its outer loops
and in none of its holes (even-odd test in x, y).

usage: b9_footprint_score.py SEGMENTS.ply OUTLINES.geojson [PICTURE.ply] [MIN_HEIGHT=2.5]
SEGMENTS.ply: pointsurf's output with the fields `label` and `segment`. Prints JSON."""
import json
import sys

import numpy as np

from b9_outline_picture import feature_rings, outline_points, read_ply, write_picture

CLASSES = {0: "ground", 1: "vegetation", 2: "roof"}
# Picture colours: ground sand, vegetation green, roof red; unstroked points grey, darker the
# higher above the ground (235 at the ground, 90 at 15 m and above).
COLOURS = {0: (214, 180, 110), 1: (40, 150, 40), 2: (215, 40, 40)}


def inside_loop(xy, loop):
    """Even-odd test of the points xy (N x 2) against a closed loop (M x 2)."""
    inside = np.zeros(len(xy), dtype=bool)
    a, b = loop, np.roll(loop, 1, axis=0)
    for (ax, ay), (bx, by) in zip(a, b):
        crosses = (ay > xy[:, 1]) != (by > xy[:, 1])
        with np.errstate(divide="ignore", invalid="ignore"):
            x_at = (bx - ax) * (xy[:, 1] - ay) / (by - ay) + ax
        inside ^= crosses & (xy[:, 0] < x_at)
    return inside


def footprint_mask(xy, features, segments):
    """Points (x, y) inside the footprint of any of `segments`: inside a Polygon's outer ring and
    in none of its holes."""
    mask = np.zeros(len(xy), dtype=bool)
    for f in features:
        if f["properties"]["group"] not in segments or f["geometry"]["type"] != "Polygon":
            continue
        outer, *holes = [ring[:-1, :2] for ring in feature_rings(f)]
        inside = inside_loop(xy, outer)
        for hole in holes:
            inside &= ~inside_loop(xy, hole)
        mask |= inside
    return mask


def main():
    cloud = read_ply(sys.argv[1])
    features = json.load(open(sys.argv[2]))["features"]
    picture = sys.argv[3] if len(sys.argv) > 3 else None
    min_height = float(sys.argv[4]) if len(sys.argv) > 4 else 2.5
    seg, label = cloud["segment"], cloud["label"]
    xyz = np.stack([cloud["x"], cloud["y"], cloud["z"]], axis=1)
    ground = float(np.median(xyz[seg == 0, 2]))
    outlined = sorted({f["properties"]["group"] for f in features})
    buildings = [s for s in outlined if np.median(xyz[seg == s, 2]) - ground >= min_height]
    # Origin at the tile's corner: the even-odd test in georeferenced coordinates loses digits.
    origin = xyz[:, :2].min(axis=0)
    shifted = [{"properties": f["properties"], "geometry": {"type": f["geometry"]["type"], "coordinates":
                [(ring - [*origin, 0.0]).tolist() for ring in feature_rings(f)]}} for f in features if f["geometry"]["type"] == "Polygon"]
    inside = footprint_mask(xyz[:, :2] - origin, shifted, buildings)
    counts = {name: int((label == c).sum()) for c, name in CLASSES.items()}
    hits = {name: int((inside & (label == c)).sum()) for c, name in CLASSES.items()}
    inside_strokes = sum(hits.values())
    out = {"ground_z": round(ground, 3), "min_height": min_height, "outlined_segments": len(outlined), "building_segments": buildings,
           "strokes": counts, "inside": hits,
           "roof_recall": round(hits["roof"] / counts["roof"], 4),
           "ground_inside": round(hits["ground"] / counts["ground"], 4),
           "vegetation_inside": round(hits["vegetation"] / counts["vegetation"], 4),
           "precision": round(hits["roof"] / max(inside_strokes, 1), 4),
           "iou_strokes": round(hits["roof"] / (counts["roof"] + hits["ground"] + hits["vegetation"]), 4)}
    print(json.dumps(out))
    if picture:
        grey = np.clip(235 - (xyz[:, 2] - ground) * (145 / 15), 90, 235)
        rgb = np.array([COLOURS.get(int(c), (g, g, g)) for c, g in zip(label, grey)], dtype=np.uint8)
        kept = [f for f in features if f["properties"]["group"] in buildings]
        line_xyz = outline_points(kept, 0.05)
        write_picture(picture, np.concatenate([xyz, line_xyz]), np.concatenate([rgb, np.zeros((len(line_xyz), 3), np.uint8)]),
                      np.concatenate([label, np.full(len(line_xyz), -2, np.int32)]))


if __name__ == "__main__":
    main()
