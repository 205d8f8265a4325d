#!/usr/bin/python3
"""femp: write the scan path of hatched layers over a rectangle, in one of
the formats femp reads ('Laser/Scan path format', doc/inputs.md):
adamantine_segment, adamantine_event_series, additivefoam, or femp's own
(one layer, no dwell).

Each layer: an optional border contour (the rectangle traced at an inset),
then parallel hatch lines 'hatch spacing' apart, at an angle that turns by
'rotation' degrees from one layer to the next, scanned in alternating
directions (bidirectional) or all in the same direction; the beam jumps
between lines with the laser off at the jump speed; between layers the laser
stays off for 'layer dwell' seconds and the next layer lies 'layer
thickness' higher. Units: m, s, W (W/m for a 2D femp scene).

Example (3 layers of 0.5 mm x 0.5 mm, 80 um hatch, 67 degree rotation):
  contrib/scan_path_generator.py --region 0 0 5e-4 5e-4 --hatch 80e-6 \\
      --layers 3 --rotation 67 --border --format additivefoam -o path.txt
"""
import argparse
import math
import sys


def clip_line(s, angle, box):
    """End points of the line {n.p = s} (direction (cos a, sin a)) inside
    box = (x0, y0, x1, y1), or None."""
    d = (math.cos(angle), math.sin(angle))
    n = (-d[1], d[0])
    base = (s * n[0], s * n[1])
    t_lo, t_hi = -math.inf, math.inf
    for k, (lo, hi) in enumerate(((box[0], box[2]), (box[1], box[3]))):
        if abs(d[k]) < 1e-15:
            if base[k] < lo - 1e-15 or base[k] > hi + 1e-15:
                return None
            continue
        ta, tb = (lo - base[k]) / d[k], (hi - base[k]) / d[k]
        t_lo, t_hi = max(t_lo, min(ta, tb)), min(t_hi, max(ta, tb))
    if t_hi - t_lo <= 1e-12:
        return None
    return ((base[0] + t_lo * d[0], base[1] + t_lo * d[1]),
            (base[0] + t_hi * d[0], base[1] + t_hi * d[1]))


def hatch_lines(box, spacing, angle, bidirectional):
    """Hatch segments filling box at angle, spacing apart, centred."""
    n = (-math.sin(angle), math.cos(angle))
    corners = [(box[0], box[1]), (box[2], box[1]), (box[0], box[3]),
               (box[2], box[3])]
    proj = [c[0] * n[0] + c[1] * n[1] for c in corners]
    lo, hi = min(proj), max(proj)
    count = max(1, int(math.floor((hi - lo) / spacing + 1e-9)))
    first = lo + 0.5 * ((hi - lo) - (count - 1) * spacing)
    lines = []
    for i in range(count):
        seg = clip_line(first + i * spacing, angle, box)
        if seg is None:
            continue
        if bidirectional and len(lines) % 2 == 1:
            seg = (seg[1], seg[0])
        lines.append(seg)
    return lines


def build_moves(a):
    """The path as moves (kind, x, y, z, power, value): kind 'spot' (value:
    dwell, s) or 'line' (value: speed, m/s); the point is where the move
    ends. The first move places the beam."""
    x0, y0, x1, y1 = a.region
    moves = []
    here = None

    def go(p, z, power, speed):
        nonlocal here
        if here is None:
            moves.append(('spot', p[0], p[1], z, 0.0, a.start_dwell))
        elif math.dist(here[:2], p) > 1e-12 or abs(here[2] - z) > 1e-12:
            moves.append(('line', p[0], p[1], z, power, speed))
        here = (p[0], p[1], z)

    for layer in range(a.layers):
        z = a.z0 + layer * a.layer_thickness
        if layer > 0 and a.layer_dwell > 0:
            moves.append(('spot', here[0], here[1], here[2], 0.0,
                          a.layer_dwell))
        inset = 0.0
        if a.border:
            c = a.border_inset
            ring = [(x0 + c, y0 + c), (x1 - c, y0 + c), (x1 - c, y1 - c),
                    (x0 + c, y1 - c), (x0 + c, y0 + c)]
            go(ring[0], z, 0.0, a.jump_speed)
            for p in ring[1:]:
                go(p, z, a.power, a.speed)
            inset = c + a.hatch_inset
        box = (x0 + inset, y0 + inset, x1 - inset, y1 - inset)
        if box[2] <= box[0] or box[3] <= box[1]:
            sys.exit('scan_path_generator: the border leaves no room for '
                     'hatches')
        angle = math.radians(a.angle + layer * a.rotation)
        for start, end in hatch_lines(box, a.hatch, angle, a.bidirectional):
            go(start, z, 0.0, a.jump_speed)
            go(end, z, a.power, a.speed)
    return moves


def timeline(moves):
    """(end time, power) of every move."""
    t, out, prev = 0.0, [], None
    for kind, x, y, z, power, value in moves:
        if kind == 'spot':
            t += value
        else:
            t += math.dist((x, y, z), prev) / value
        out.append((t, power))
        prev = (x, y, z)
    return out


def write(moves, a, out):
    fmt = a.format
    nominal = a.nominal_power if a.nominal_power > 0 else a.power
    times = timeline(moves)
    if fmt == 'adamantine_segment':
        out.write('Number of path segments\n%d\n' % len(moves))
        out.write('Mode x y z pmod param\n')
        for kind, x, y, z, power, value in moves:
            out.write('%d %.9g %.9g %.9g %.9g %.9g\n' %
                      (kind == 'spot', x, y, z, power / nominal, value))
    elif fmt == 'additivefoam':
        out.write('Mode X(m) Y(m) Z(m) Power(W) Parameter\n')
        for kind, x, y, z, power, value in moves:
            out.write('%d %.9g %.9g %.9g %.9g %.9g\n' %
                      (kind == 'spot', x, y, z, power, value))
    elif fmt == 'adamantine_event_series':
        # Event k: time the beam reaches point k, and the power factor of
        # the move that follows it.
        for k, (kind, x, y, z, power, value) in enumerate(moves):
            following = moves[k + 1][4] / nominal if k + 1 < len(moves) else 0
            out.write('%.12g, %.9g, %.9g, %.9g, %.9g\n' %
                      (times[k][0], x, y, z, following))
    else:  # femp: 'x0 y0 x1 y1 speed power', in one plane, no dwells
        if a.layers > 1 or any(m[0] == 'spot' for m in moves[1:]):
            sys.exit('scan_path_generator: the femp format holds one layer '
                     'without dwells; use another format')
        for prev, m in zip(moves, moves[1:]):
            out.write('%.9g %.9g %.9g %.9g %.9g %.9g\n' %
                      (prev[1], prev[2], m[1], m[2], m[5], m[4]))
    energy = sum((t1 - t0) * p for (t0, _), (t1, p) in
                 zip([(0.0, 0.0)] + times[:-1], times))
    sys.stderr.write('scan_path_generator: %d moves, %.6g s, emitted energy '
                     '%.6g J\n' % (len(moves), times[-1][0], energy))


def main():
    p = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument('--region', nargs=4, type=float, required=True,
                   metavar=('X0', 'Y0', 'X1', 'Y1'),
                   help='rectangle to fill, m')
    p.add_argument('--hatch', type=float, required=True,
                   help='hatch spacing, m')
    p.add_argument('--angle', type=float, default=0.,
                   help='hatch angle of the first layer, degrees from x')
    p.add_argument('--rotation', type=float, default=0.,
                   help='hatch rotation from one layer to the next, degrees '
                   '(67 is common)')
    p.add_argument('--unidirectional', dest='bidirectional',
                   action='store_false',
                   help='scan every hatch in the same direction (default: '
                   'alternate)')
    p.add_argument('--border', action='store_true',
                   help='trace a border contour before the hatches')
    p.add_argument('--border-inset', type=float, default=None,
                   help='inset of the contour from the region, m (default: '
                   'half the hatch spacing)')
    p.add_argument('--hatch-inset', type=float, default=None,
                   help='gap between the contour and the hatched area, m '
                   '(default: the hatch spacing)')
    p.add_argument('--layers', type=int, default=1)
    p.add_argument('--layer-thickness', type=float, default=30e-6,
                   help='m')
    p.add_argument('--z0', type=float, default=0., help='height of the '
                   'first layer, m')
    p.add_argument('--layer-dwell', type=float, default=0.,
                   help='laser off between layers, s')
    p.add_argument('--start-dwell', type=float, default=1e-6,
                   help='time the beam sits, off, at its first point, s '
                   '(adamantine wants it positive)')
    p.add_argument('--power', type=float, default=200., help='W')
    p.add_argument('--nominal-power', type=float, default=0.,
                   help='adamantine formats: the power written as factor '
                   '1 (\'Laser/Power\'), W; default: --power')
    p.add_argument('--speed', type=float, default=1., help='scan speed, m/s')
    p.add_argument('--jump-speed', type=float, default=5.,
                   help='speed of the moves with the laser off, m/s')
    p.add_argument('--format', default='additivefoam',
                   choices=['adamantine_segment', 'adamantine_event_series',
                            'additivefoam', 'femp'])
    p.add_argument('-o', '--output', default='-', help="file ('-': stdout)")
    a = p.parse_args()
    if a.border_inset is None:
        a.border_inset = 0.5 * a.hatch
    if a.hatch_inset is None:
        a.hatch_inset = a.hatch
    for name in ('hatch', 'speed', 'jump_speed'):
        if getattr(a, name) <= 0:
            p.error('--%s must be positive' % name.replace('_', '-'))
    if a.layers < 1 or a.power < 0 or a.layer_dwell < 0 or a.start_dwell < 0:
        p.error('--layers must be >= 1, --power and the dwells >= 0')
    if a.region[2] <= a.region[0] or a.region[3] <= a.region[1]:
        p.error('--region must be X0 Y0 X1 Y1 with X1 > X0 and Y1 > Y0')
    moves = build_moves(a)
    if a.output == '-':
        write(moves, a, sys.stdout)
    else:
        with open(a.output, 'w') as out:
            write(moves, a, out)


if __name__ == '__main__':
    main()
