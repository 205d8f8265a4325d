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
(without the APIC affine part). Standard library only.
"""
import array
import base64
import math
import os
import re
import struct
import sys
import zlib


def read_vtu(path):
    """The binary (zlib) data arrays of a deal.II VTU file, by name."""
    text = open(path).read()
    out = {}
    pat = (r'<DataArray type="(\w+)"(?: Name="(\w+)")?'
           r'(?: NumberOfComponents="(\d+)")? format="binary">\s*(\S+)\s*'
           r'</DataArray>')
    for m in re.finditer(pat, text):
        typ, name, nc, data = m.group(1), m.group(2) or "Points", \
            int(m.group(3) or 1), m.group(4)
        nb = struct.unpack("<I", base64.b64decode(data[:8])[:4])[0]
        hlen = 4 * math.ceil(4 * (3 + nb) / 3)
        head = struct.unpack("<%dI" % (3 + nb), base64.b64decode(data[:hlen]))
        body, raw, off = base64.b64decode(data[hlen:]), b"", 0
        for c in head[3:]:
            raw += zlib.decompress(body[off:off + c])
            off += c
        code = {"Float32": "f", "Float64": "d", "Int32": "i", "UInt32": "I",
                "Int64": "q", "UInt8": "B"}.get(typ, "f")
        a = array.array(code)
        a.frombytes(raw)
        out[name] = a if nc == 1 else [a[i * nc:(i + 1) * nc]
                                       for i in range(len(a) // nc)]
    return out


def scene_entry(text, section, name, default):
    path, value = [], default
    for line in text.split("\n"):
        s = line.split("#")[0].strip()
        if s.startswith("subsection "):
            path.append(s[11:].strip())
        elif s == "end":
            path.pop()
        else:
            m = re.match(r"set\s+(.*?)\s*=\s*(.*)$", s)
            if m and "/".join(path) == section and m.group(1) == name:
                value = m.group(2).strip()
    return value


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


def main():
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    scene = open(sys.argv[1]).read()
    E = table(scene_entry(scene, "Solid/Material", "Young's modulus", "1.93e11"))
    nu = float(scene_entry(scene, "Solid/Material", "Poisson's ratio", "0.3"))
    s = float(scene_entry(scene, "Solid", "Mass scaling factor", "1"))
    pv = sys.argv[2]
    pieces = re.findall(r'<Piece Source="([^"]+)"', open(pv).read())
    U = K = 0.0
    n = 0
    for piece in pieces:
        d = read_vtu(os.path.join(os.path.dirname(pv), piece))
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
