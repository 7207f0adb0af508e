#!/usr/bin/python3
"""A voxelised bumpy sphere (integer coordinates, radius R voxels, offset 512) with smooth colours
and a checker, and its colour-noise (sigma 10) distortion, as binary PLY: GraphSIM's benchmark
pair (its neighbourhood radius needs voxel-scale coordinates). Usage: gen_voxel_sphere.py R PREFIX
(writes PREFIX_ref.ply and PREFIX_cnoise10.ply; R = 290 gives about 1.17M points)."""
import sys

import numpy as np

radius, prefix = float(sys.argv[1]), sys.argv[2]
rng = np.random.default_rng(42)
v = rng.normal(size=(int(40 * radius * radius), 3))
v /= np.linalg.norm(v, axis=1)[:, None]
bump = 1 + 0.05 * np.sin(5 * np.arctan2(v[:, 1], v[:, 0])) * np.cos(4 * np.arccos(np.clip(v[:, 2], -1, 1)))
xyz = np.unique(np.rint(v * (radius * bump)[:, None]) + 512, axis=0)
rng.shuffle(xyz)
checker = 20 * ((xyz // 16).sum(1) % 2)[:, None]
rgb = np.clip(128 + 100 * np.sin(xyz / 37.0) + checker, 0, 255).astype(np.uint8)


def write(path, colours):
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
            "property float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
            "property uchar blue\nend_header\n") % len(xyz)
    rec = np.zeros(len(xyz), dtype=[("p", "<f4", 3), ("c", "u1", 3)])
    rec["p"] = xyz
    rec["c"] = colours
    with open(path, "wb") as f:
        f.write(head.encode())
        f.write(rec.tobytes())


write(prefix + "_ref.ply", rgb)
noisy = np.clip(np.rint(rgb + rng.normal(scale=10, size=rgb.shape)), 0, 255).astype(np.uint8)
write(prefix + "_cnoise10.ply", noisy)
