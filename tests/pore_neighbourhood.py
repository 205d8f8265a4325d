#!/usr/bin/env python3
# Test of contrib/femp_post.py pore_neighbourhood_summary() (doc/builds.md,
# the stress around the pores of a build): a grid output of 5 x 5 x 5
# cells of 8 um, one pore cell in the middle (2, 2, 2), one gas cell in a
# corner, one partly filled cell (alpha 0.3) above the pore, the rest
# metal with sigma_xx = 10 i + j + 100 k MPa (i, j, k the cell's index)
# and von Mises 200 + i MPa. The reference is counted cell by cell here:
# 'next' = the metal face neighbours of the pore (5: the sixth is the
# partly filled cell), 'away' = the metal more than far = 1 cells from
# it (largest index distance) with k >= 1 (73 of the 100 such cells lie
# outside the 3 x 3 x 3 cube). Then a pore cell on the x face (0, 2, 2):
# 5 face neighbours (none wrapped round to i = 4). Prints each error and
# fails above 1e-12 (relative) or on a wrong count.
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "contrib"))
import femp_post  # noqa: E402
import numpy as np  # noqa: E402

N, H = 5, 8e-6


def grid(pore_at):
    cells = [(i, j, k) for k in range(N) for j in range(N) for i in range(N)]
    centres = np.array([[(i + 0.5) * H, (j + 0.5) * H, (k + 0.5) * H]
                        for i, j, k in cells])
    alpha = np.ones(len(cells))
    vm = np.array([200e6 + i * 1e6 for i, j, k in cells])
    sxx = np.array([(10 * i + j + 100 * k) * 1e6 for i, j, k in cells])
    pore = np.zeros(len(cells))
    for n, c in enumerate(cells):
        if c == pore_at:
            pore[n], alpha[n], vm[n] = 1, 0, 0
        elif c == (0, 0, 0):
            alpha[n], vm[n] = 0, 0
        elif c == (2, 2, 3):
            alpha[n] = 0.3
    g = femp_post.Fields({"alpha": alpha, "von_mises": vm, "sigma_xx": sxx,
                          "pore": pore}, 1e-3, 1, centres, "grid")
    return g, cells, alpha, vm, sxx


def reference(cells, alpha, vm, pore_at, within_k):
    metal = [n for n, c in enumerate(cells)
             if vm[n] != 0 and alpha[n] >= 0.5 and c != pore_at]
    nxt = [n for n in metal
           if sum(abs(a - b) for a, b in zip(cells[n], pore_at)) == 1]
    away = [n for n in metal if cells[n][2] >= within_k and
            max(abs(a - b) for a, b in zip(cells[n], pore_at)) > 1]
    return nxt, away


def check(label, got, want):
    good = got == want
    print("%-34s %d (expected %d) %s"
          % (label, got, want, "ok" if good else "FAILED"))
    return good


def main():
    ok = True
    pore_at = (2, 2, 2)
    g, cells, alpha, vm, sxx = grid(pore_at)
    within = g.centres[:, 2] >= H
    got = femp_post.pore_neighbourhood_summary(
        g, alpha_min=0.5, fields=("sigma_xx", "von_mises"), far=1,
        within=within)
    nxt, away = reference(cells, alpha, vm, pore_at, 1)
    ok &= check("mask cells", got["mask"], 1)
    ok &= check("next to the pore", got["next"], 5)
    ok &= check("next to the pore (counted here)", len(nxt), 5)
    ok &= check("away from the pore", got["away"], 73)
    ok &= check("away from the pore (counted here)", len(away), 73)
    ok &= check("the same cells next to it",
                int(sorted(got["next_cells"]) == sorted(nxt)), 1)
    for field, v in (("sigma_xx", sxx), ("von_mises", vm)):
        for region, cells_of in (("next", nxt), ("away", away)):
            want = (np.mean(v[cells_of]), np.min(v[cells_of]),
                    np.max(v[cells_of]))
            for stat, w in zip(("mean", "min", "max"), want):
                e = abs(got[field][region][stat] - w) / abs(w)
                good = e <= 1e-12
                ok &= good
                print("%-9s %-4s %-4s %.6g Pa, relative error %.1e %s"
                      % (field, region, stat, got[field][region][stat], e,
                         "ok" if good else "FAILED"))
    pore_at = (0, 2, 2)
    g, cells, alpha, vm, sxx = grid(pore_at)
    got = femp_post.pore_neighbourhood_summary(g, fields=("von_mises",),
                                               far=1)
    nxt, _ = reference(cells, alpha, vm, pore_at, 0)
    ok &= check("pore on the x face: next to it", got["next"], len(nxt))
    ok &= check("pore on the x face: next (count)", got["next"], 5)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
