# SPDX-License-Identifier: GPL-3.0-or-later
"""compare_distances.py DIAGONAL OURS_UNSIGNED.bin OURS_SIGNED.bin OURS_WINDING.bin OPEN3D.npy OPEN3D_SIGNED.npy

Agreement of magnitudes with Open3D (max |difference| / diagonal) and of signs with the
winding-number oracle (ours) and Open3D's signed distance; one JSON object."""
import json
import sys

import numpy as np


def main():
    diagonal = float(sys.argv[1])
    unsigned = np.fromfile(sys.argv[2], dtype=np.float64)
    signed = np.fromfile(sys.argv[3], dtype=np.float64)
    winding = np.fromfile(sys.argv[4], dtype=np.float64)
    o3d = np.load(sys.argv[5])
    o3d_signed = np.load(sys.argv[6])
    print(json.dumps({
        "max_abs_diff_over_diagonal": float(np.max(np.abs(unsigned - o3d)) / diagonal),
        "signed_vs_unsigned_magnitude": float(np.max(np.abs(np.abs(signed) - unsigned)) / diagonal),
        "sign_agreement_with_winding": float(np.mean(np.sign(signed) == np.sign(winding))),
        "open3d_negative_share": float(np.mean(o3d_signed < 0)),
        "negative_share": float(np.mean(signed < 0)),
    }))


if __name__ == "__main__":
    main()
