#!/usr/bin/env python3
"""Stored elastic energy and kinetic energy of the solid material points in a
femp point output (doc/speed_accuracy.md, "The solid's stress work under
mass scaling"): the quasi-static gauge K / U_el, which, unlike the
kinetic/internal column of solid_energy.csv, does not divide by the
numerical transfer loss.

  contrib/solid_elastic_energy.py SCENE.prm OUTPUT_DIR/points_00001.pvtu

U_el = sum_p V_p sigma_p : C(T_p)^-1 : sigma_p / 2 with E(T) and nu from the
scene ('Solid/Material'), over the MPM points only (the FE zone is not in
the point files); K = sum_p s m_p |v_p|^2 / 2 with the mass scaling s
(without the APIC affine part). The point output and the scene are read
by contrib/femp_post.py (numpy; VTU or HDF5 output).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import femp_post  # noqa: E402


def scene_entry(values, section, name, default):
    """The text of Section/Name in the scene's entries, else default."""
    return values.get(section + "/" + name, default)


def table(text):
    """A constant or 'T1:v1, T2:v2, ...' as a function of T."""
    if ":" not in text:
        v = float(text)
        return lambda T: v
    pts = [tuple(float(x) for x in p.split(":")) for p in text.split(",")]

    def f(T):
        if T <= pts[0][0]:
            return pts[0][1]
        for (a, fa), (b, fb) in zip(pts, pts[1:]):
            if T <= b:
                return fa + (fb - fa) * (T - a) / (b - a)
        return pts[-1][1]
    return f


def point_output(path):
    """The points output a path names: OUTPUT_DIR/points_<n>.pvtu or
    OUTPUT_DIR/points_<n>.h5."""
    d, name = os.path.split(path)
    n = int(name.split("_")[1].split(".")[0])
    return femp_post.Run(d or ".").points(n)


def main():
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    scene = femp_post.read_parameters(sys.argv[1])
    E = table(scene_entry(scene, "Solid/Material", "Young's modulus", "1.93e11"))
    nu = float(scene_entry(scene, "Solid/Material", "Poisson's ratio", "0.3"))
    s = float(scene_entry(scene, "Solid", "Mass scaling factor", "1"))
    p = point_output(sys.argv[2])
    d = {k: p[k].tolist() for k in
         ("mass", "state", "volume", "temperature", "stress_xx", "stress_yy",
          "stress_zz", "stress_xy", "stress_xz", "stress_yz", "velocity_x",
          "velocity_y", "velocity_z")}
    U = K = 0.0
    n = 0
    for i in range(len(d["mass"])):
        if d["state"][i] == 2:  # fluid points are not in the solid
            continue
        xx, yy, zz = d["stress_xx"][i], d["stress_yy"][i], d["stress_zz"][i]
        xy, xz, yz = d["stress_xy"][i], d["stress_xz"][i], d["stress_yz"][i]
        U += d["volume"][i] * ((xx * xx + yy * yy + zz * zz)
                               - 2 * nu * (xx * yy + yy * zz + zz * xx)
                               + 2 * (1 + nu) * (xy * xy + xz * xz + yz * yz)
                               ) / (2 * E(d["temperature"][i]))
        K += 0.5 * s * d["mass"][i] * (d["velocity_x"][i] ** 2 +
                                       d["velocity_y"][i] ** 2 +
                                       d["velocity_z"][i] ** 2)
        n += 1
    print("solid points %d, mass scaling %g" % (n, s))
    print("elastic energy U_el = %.4g J, kinetic K = %.4g J, K/U_el = %.3g"
          % (U, K, K / U if U > 0 else float("nan")))


if __name__ == "__main__":
    main()
