#!/usr/bin/env python3
"""Free vibrations of a slab of femp's finite elements (doc/solid.md,
"Quasi-static cooling"): eight-node hexahedra of side h with one-point
integration and no hourglass control (as the build scenes run), lumped
masses s rho h^3 / 8 per corner, periodic in x and y (nx x ny cells), nz
cells tall, the bottom node layer fixed and the top one free.

  contrib/fe_zone_modes.py [--E 193e9] [--nu 0.3] [--rho 7955] [--h 8e-6]
      [--s 1] [--nx 4] [--ny 4] [--nz 6] [--hourglass 0]

Prints the periods that the most modes share, for nz and for 2 nz cells
(a count that grows with the height is a band whose frequency does not
depend on the vertical wave number: its modes do not travel up or down),
and for the period 2 pi h sqrt(s rho / (2 mu)): how many modes have it,
the largest |tr eps| / |eps| over their elements (0: isochoric, no work
of the bulk viscosity) and the share of each node layer in the mode of
that family that is largest at one node of the first free layer.
--hourglass k adds the stiffness k (lambda + 2 mu) h / 8 per hourglass
mode and direction. numpy only.
"""
import argparse
import itertools
from collections import Counter

import numpy as np


def slab(a):
    lam = a.E * a.nu / ((1 + a.nu) * (1 - 2 * a.nu))
    mu = a.E / (2 * (1 + a.nu))
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[range(3), range(3)] += 2 * mu
    D[3, 3] = D[4, 4] = D[5, 5] = mu
    corners = [(c & 1, (c >> 1) & 1, (c >> 2) & 1) for c in range(8)]
    sg = np.array([[2 * c[0] - 1, 2 * c[1] - 1, 2 * c[2] - 1] for c in corners])
    B = np.zeros((6, 24))  # gradient at the centre, Voigt xx yy zz xy xz yz
    for c in range(8):
        g = sg[c] / (4 * a.h)
        B[0, 3 * c], B[1, 3 * c + 1], B[2, 3 * c + 2] = g
        B[3, 3 * c], B[3, 3 * c + 1] = g[1], g[0]
        B[4, 3 * c], B[4, 3 * c + 2] = g[2], g[0]
        B[5, 3 * c + 1], B[5, 3 * c + 2] = g[2], g[1]
    Ke = a.h ** 3 * B.T @ D @ B
    if a.hourglass > 0:
        for gm in (sg[:, 0] * sg[:, 1], sg[:, 1] * sg[:, 2],
                   sg[:, 0] * sg[:, 2], sg[:, 0] * sg[:, 1] * sg[:, 2]):
            for d in range(3):
                v = np.zeros(24)
                v[d::3] = gm
                Ke += a.hourglass * (lam + 2 * mu) * a.h / 8 * np.outer(v, v)
    nx, ny, nz = a.nx, a.ny, a.nz

    def node(i, j, k):
        return (k * ny + j % ny) * nx + i % nx

    n = nx * ny * (nz + 1)
    K = np.zeros((3 * n, 3 * n))
    M = np.zeros(3 * n)
    dofs = []
    for i, j, k in itertools.product(range(nx), range(ny), range(nz)):
        ids = [node(i + c[0], j + c[1], k + c[2]) for c in corners]
        dof = [3 * m + d for m in ids for d in range(3)]
        dofs.append(dof)
        K[np.ix_(dof, dof)] += Ke
        M[dof] += a.s * a.rho * a.h ** 3 / 8
    free = np.arange(3 * nx * ny, 3 * n)  # the bottom layer fixed
    Mf = M[free]
    w2, V = np.linalg.eigh(K[np.ix_(free, free)] / np.sqrt(np.outer(Mf, Mf)))
    U = np.zeros((3 * n, len(w2)))
    U[free] = V / np.sqrt(Mf)[:, None]
    return w2, U, B, dofs, mu


def periods(w2):
    return 2 * np.pi / np.sqrt(np.maximum(w2, 1e-300))


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    for name, default in (("E", 193e9), ("nu", 0.3), ("rho", 7955.0),
                          ("h", 8e-6), ("s", 1.0), ("hourglass", 0.0)):
        ap.add_argument("--" + name, type=float, default=default)
    for name, default in (("nx", 4), ("ny", 4), ("nz", 6)):
        ap.add_argument("--" + name, type=int, default=default)
    a = ap.parse_args()
    w2, U, B, dofs, mu = slab(a)
    a2 = argparse.Namespace(**vars(a))
    a2.nz = 2 * a.nz
    w2_tall = slab(a2)[0]
    for nz, w in ((a.nz, w2), (a2.nz, w2_tall)):
        c = Counter(np.round(periods(w[w > 1e-12 * w.max()]) * 1e9, 3))
        print("nz = %d: periods (ns) shared by the most modes:" % nz,
              ", ".join("%g (%d)" % x for x in c.most_common(3)))
    T = 2 * np.pi * a.h * np.sqrt(a.s * a.rho / (2 * mu))
    fam = np.nonzero(np.abs(w2 * (a.s * a.rho * a.h ** 2) / (2 * mu) - 1) < 1e-6)[0]
    print("2 pi h sqrt(s rho / (2 mu)) = %.4g ns: %d modes" % (T * 1e9, len(fam)))
    if len(fam) == 0:
        return
    tr = max(abs(e[:3].sum()) / np.abs(e).max()
             for m in fam for e in (B @ U[d, m] for d in dofs)
             if np.abs(e).max() > 0)
    print("largest |tr eps| / |eps| over their elements: %.1e" % tr)
    # The mode of the family that is largest at the vertical component of
    # one node of the first free layer (node 0 of layer 1).
    x = U[:, fam] @ U[3 * a.nx * a.ny + 2, fam]
    x = x.reshape(a.nz + 1, a.ny, a.nx, 3)
    share = (x ** 2).sum(axis=(1, 2, 3))
    print("that mode's share per node layer (bottom first):",
          " ".join("%.3f" % v for v in share / share.sum()))
    print("its v_z in layer 1 (rows y, columns x), over the largest:")
    print(np.round(x[1, :, :, 2] / np.abs(x).max(), 2))


if __name__ == "__main__":
    main()
