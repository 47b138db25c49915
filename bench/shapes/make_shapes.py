#!/usr/bin/python3
"""Genus-0 test solids beyond brains (issue 15) as binary masks on a 1 mm grid (NIfTI), for
bench/shapes/run.sh: each is a union of simple solids given by signed distances, so the shape
is exact and reproducible.

  limbs    a ball (radius 22 mm) with 6 limbs of aspect 5:1 (radius 6 mm, 60 mm long)
  hand     a palm (ellipsoid 45 x 55 x 16 mm), 5 fingers (radius 6.5 mm, 32-48 mm) and a wrist
  slab     a thin curved slab: a spherical cap of a 7 mm thick shell of radius 60 mm, 65 degrees
  coil     a tube (radius 6.5 mm) along 2.25 turns of a helix (radius 24 mm, pitch 22 mm), ends capped
  kidney   a compact control: a bent ellipsoid (110 x 60 x 50 mm)
  femur    a long bone: a shaft (radius 9 mm, 110 mm) with a neck and a head (radius 21 mm) at
           one end and two condyles at the other

Usage: make_shapes.py OUT_DIR [NAME ...]
"""
import os
import sys

import nibabel as nib
import numpy as np


def grid(extent):
    """World coordinates (3, n, n, n) of a 1 mm grid covering [-extent, extent]^3."""
    ax = np.arange(-extent, extent + 1, 1.0)
    return np.stack(np.meshgrid(ax, ax, ax, indexing="ij")), ax


def capsule(p, a, b, r):
    """Signed distance to the capsule of radius r around segment a-b."""
    a, b = np.asarray(a, float)[:, None, None, None], np.asarray(b, float)[:, None, None, None]
    ab = b - a
    t = np.clip(((p - a) * ab).sum(0) / (ab * ab).sum(), 0, 1)
    return np.linalg.norm(p - (a + t * ab), axis=0) - r


def ellipsoid(p, c, radii):
    c, radii = np.asarray(c, float)[:, None, None, None], np.asarray(radii, float)[:, None, None, None]
    return (np.linalg.norm((p - c) / radii, axis=0) - 1) * radii.min()


def limbs(p):
    d = np.linalg.norm(p, axis=0) - 22
    for axis in np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0.6, 0.6, -0.53]]):
        axis = axis / np.linalg.norm(axis)
        d = np.minimum(d, capsule(p, axis * 15, axis * 75, 6))
    return d


def hand(p):
    d = ellipsoid(p, [0, 0, 0], [23, 28, 8])
    for x, length, angle in [(-17, 34, 0.5), (-8, 44, 0.12), (2, 48, 0.0), (12, 44, -0.1), (21, 36, -0.25)]:
        base = np.array([x, 22, 0])
        direction = np.array([np.sin(-angle), np.cos(angle), 0])
        d = np.minimum(d, capsule(p, base, base + length * direction, 6.5))
    thumb = np.array([-22, -4, 0])
    d = np.minimum(d, capsule(p, thumb, thumb + 36 * np.array([-0.8, 0.6, 0]), 7))
    return np.minimum(d, capsule(p, [0, -22, 0], [0, -48, 0], 15))


def slab(p):
    q = p + np.array([0, 0, 40.0])[:, None, None, None]  # sphere centre 40 mm below the grid centre
    r = np.linalg.norm(q, axis=0)
    shell = np.abs(r - 60) - 3.5
    polar = np.arccos(np.clip(q[2] / np.maximum(r, 1e-9), -1, 1))
    cap = (polar - np.radians(65)) * 60
    return np.maximum(shell, cap)


def coil(p):
    t = np.linspace(0, 2.25 * 2 * np.pi, 240)
    pts = np.stack([24 * np.cos(t), 24 * np.sin(t), 22 * t / (2 * np.pi) - 24.75], axis=1)
    d = np.full(p.shape[1:], np.inf)
    for a, b in zip(pts[:-1], pts[1:]):
        d = np.minimum(d, capsule(p, a, b, 6.5))
    return d


def kidney(p):
    x, y, z = p
    bend = 0.004 * x * x
    return ellipsoid(np.stack([x, y - bend + 10, z]), [0, 0, 0], [55, 30, 25])


def femur(p):
    d = capsule(p, [0, 0, -55], [0, 0, 55], 9)
    d = np.minimum(d, capsule(p, [0, 0, 50], [-22, 0, 68], 11))  # the neck, bent medially
    d = np.minimum(d, np.linalg.norm(p - np.array([-30, 0, 74.0])[:, None, None, None], axis=0) - 21)
    for x in (-13, 13):  # the condyles
        d = np.minimum(d, ellipsoid(p, [x, 3, -62], [14, 20, 16]))
    return d


SHAPES = {"limbs": (limbs, 90), "hand": (hand, 80), "slab": (slab, 70), "coil": (coil, 60), "kidney": (kidney, 70), "femur": (femur, 100)}


def main():
    out = sys.argv[1]
    names = sys.argv[2:] or list(SHAPES)
    os.makedirs(out, exist_ok=True)
    for name in names:
        f, extent = SHAPES[name]
        p, ax = grid(extent)
        mask = (f(p) <= 0).astype(np.uint8)
        affine = np.eye(4)
        affine[:3, 3] = ax[0]
        nib.save(nib.Nifti1Image(mask, affine), os.path.join(out, f"{name}.nii.gz"))
        print(f"{name}: {int(mask.sum())} voxels ({mask.sum() / 1000:.1f} ml) on {mask.shape[0]}^3", flush=True)


if __name__ == "__main__":
    main()
