#!/usr/bin/python3
"""Stimuli for the report tests: a coloured sphere mesh and a coloured sphere cloud, each with a
distorted copy whose colour noise is on the x > 0 half only (geometry unchanged), as ASCII PLY.

Usage: make_stimuli.py OUTDIR   (writes mesh_ref.ply, mesh_dist.ply, cloud_ref.ply, cloud_dist.ply)"""
import os
import sys

import numpy as np

NOISE_SIGMA = 40.0  # colour noise, in 8-bit levels
SEED = 7


def colours(xyz):
    """Smooth colours, so that any visible difference is the noise."""
    c = 0.5 + 0.35 * np.stack([xyz[:, 1], xyz[:, 2], -xyz[:, 1]], axis=1)
    return np.clip(np.rint(255 * c), 0, 255).astype(int)


def half_noise(xyz, rgb, rng):
    noisy = rgb + np.rint(rng.normal(scale=NOISE_SIGMA, size=rgb.shape)).astype(int)
    out = np.where((xyz[:, 0] > 0)[:, None], noisy, rgb)
    return np.clip(out, 0, 255)


def uv_sphere(n_theta=96, n_phi=48):
    verts, faces = [[0.0, 1.0, 0.0]], []
    for i in range(1, n_phi):
        phi = np.pi * i / n_phi
        for j in range(n_theta):
            theta = 2 * np.pi * j / n_theta
            verts.append([np.sin(phi) * np.cos(theta), np.cos(phi), np.sin(phi) * np.sin(theta)])
    verts.append([0.0, -1.0, 0.0])
    ring = lambda i, j: 1 + (i - 1) * n_theta + j % n_theta
    for j in range(n_theta):
        faces.append([0, ring(1, j + 1), ring(1, j)])
    for i in range(1, n_phi - 1):
        for j in range(n_theta):
            a, b, c, d = ring(i, j), ring(i, j + 1), ring(i + 1, j), ring(i + 1, j + 1)
            faces += [[a, b, d], [a, d, c]]
    last = len(verts) - 1
    for j in range(n_theta):
        faces.append([last, ring(n_phi - 1, j), ring(n_phi - 1, j + 1)])
    return np.array(verts), faces


def fibonacci_sphere(n):
    i = np.arange(n) + 0.5
    phi = np.arccos(1 - 2 * i / n)
    theta = np.pi * (1 + 5 ** 0.5) * i
    return np.stack([np.cos(theta) * np.sin(phi), np.cos(phi), np.sin(theta) * np.sin(phi)], axis=1)


def write_ply(path, xyz, rgb, faces=None):
    with open(path, 'w') as f:
        f.write('ply\nformat ascii 1.0\nelement vertex %d\n' % len(xyz))
        f.write('property float x\nproperty float y\nproperty float z\n')
        f.write('property uchar red\nproperty uchar green\nproperty uchar blue\n')
        if faces:
            f.write('element face %d\nproperty list uchar int vertex_indices\n' % len(faces))
        f.write('end_header\n')
        for p, c in zip(xyz, rgb):
            f.write('%.7f %.7f %.7f %d %d %d\n' % (p[0], p[1], p[2], c[0], c[1], c[2]))
        for t in faces or []:
            f.write('3 %d %d %d\n' % tuple(t))


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    rng = np.random.default_rng(SEED)
    verts, faces = uv_sphere()
    rgb = colours(verts)
    write_ply(os.path.join(out, 'mesh_ref.ply'), verts, rgb, faces)
    write_ply(os.path.join(out, 'mesh_dist.ply'), verts, half_noise(verts, rgb, rng), faces)
    pts = fibonacci_sphere(20000)
    rgb = colours(pts)
    write_ply(os.path.join(out, 'cloud_ref.ply'), pts, rgb)
    write_ply(os.path.join(out, 'cloud_dist.ply'), pts, half_noise(pts, rgb, rng))


main()
