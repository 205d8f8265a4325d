#!/usr/bin/env python3
"""Cost per layer of a build, with and without 'Build/Hand over cooled
metal' (doc/builds.md, "Handing cooled metal to finite elements"), from
femp's logs.

    python3 contrib/plot_handover_cost.py [--per-time] [--median]
        OUT.svg LOG=label [LOG=label ...]

Each LOG is the standard output of a femp run with a layer schedule and a
progress line ('Output/Progress interval') much shorter than a layer. The
layers start at the 'Recoat: layer k at t = ...' lines (layer 1 at t = 0)
and end where the next one starts (the last one at the last progress
line); the wall time of a layer is the difference of the wall times of
the progress lines nearest to its start and its end (interpolated
linearly in the simulated time). Prints a table (layer, start, end, wall
per run, the FE zone's top after each hand-over) and draws the wall time
per layer of each run against the layer (SVG, matplotlib). The logs are
read by contrib/femp_post.py (read_printed).

--per-time: the cost of a layer is its wall time over its simulated time
(s of wall per 100 us simulated), so that layers of different lengths
(the first, which starts at 0, and the last, its track only) compare.
--median: the runs whose labels differ only after their last '_' (e.g.
without_1, without_2) form a group; the table adds the median of each
group per layer, and the chart draws the medians (the single runs thin).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import femp_post  # noqa: E402

PROGRESS = r"^t =\s*(?P<t>[0-9.eE+-]+) s\s+step.*wall\s+(?P<wall>[0-9.eE+-]+) s"
RECOAT = r"^Recoat: layer (?P<layer>\d+) at t = (?P<t>[0-9.eE+-]+) s"
RAISE = (r"the zone's top rises from (?P<from>[0-9.eE+-]+) to (?P<to>[0-9.eE+-]+) m: "
         r"(?P<elements>\d+) elements, (?P<points>\d+) points")


def read(log):
    """The progress lines (t, wall), the layers' start times (layer 1 at
    0) and the hand-overs by layer: {layer: (new top, elements, points)}."""
    with open(log) as f:
        lines = f.read().split("\n")
    p = femp_post.read_printed(lines, PROGRESS)
    r = femp_post.read_printed(lines, RECOAT)
    h = femp_post.read_printed(lines, RAISE)
    progress = list(zip(p["t"].tolist(), p["wall"].tolist()))
    starts = [0.0] + r["t"].tolist()
    taken = set(p.lines.tolist()) | set(r.lines.tolist())
    raises = {}
    for k, line in enumerate(h.lines.tolist()):
        if line in taken:
            continue
        layer = 1 + sum(1 for x in r.lines.tolist() if x < line)
        raises[layer] = (float(h["to"][k]), int(h["elements"][k]),
                         int(h["points"][k]))
    return progress, starts, raises


def wall_at(progress, t):
    for (t0, w0), (t1, w1) in zip(progress, progress[1:]):
        if t0 <= t <= t1:
            return w0 + (w1 - w0) * (t - t0) / (t1 - t0) if t1 > t0 else w1
    return progress[-1][1] if t > progress[-1][0] else progress[0][1]


def median(values):
    v = sorted(values)
    n = len(v)
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])


def main():
    args = sys.argv[1:]
    per_time = "--per-time" in args
    medians = "--median" in args
    args = [a for a in args if a not in ("--per-time", "--median")]
    if len(args) < 2:
        sys.exit(__doc__)
    out = args[0]
    unit = "s per 100 us" if per_time else "s"
    runs = []
    for arg in args[1:]:
        log, label = arg.split("=", 1)
        progress, starts, raises = read(log)
        ends = starts[1:] + [progress[-1][0]]
        walls = [wall_at(progress, e) - wall_at(progress, s)
                 for s, e in zip(starts, ends)]
        costs = [w / ((e - s) / 1e-4) if per_time else w
                 for s, e, w in zip(starts, ends, walls)]
        runs.append((label, starts, ends, costs, raises))
        print(f"# {label} ({log}): total wall {progress[-1][1]:.1f} s")
        print(f"layer, t_start (s), t_end (s), wall ({unit}), FE zone top "
              "after the hand-over (m), elements added, points handed over")
        for k, (s, e, w) in enumerate(zip(starts, ends, costs), start=1):
            r = raises.get(k)
            extra = f", {r[0]:.6g}, {r[1]}, {r[2]}" if r else ", -, 0, 0"
            print(f"{k}, {s:.6g}, {e:.6g}, {w:.2f}{extra}")
    groups = {}
    if medians:
        for label, _, _, costs, _ in runs:
            groups.setdefault(label.rsplit("_", 1)[0], []).append(costs)
        for name, members in groups.items():
            n = min(len(c) for c in members)
            groups[name] = [median([c[k] for c in members]) for k in range(n)]
            print(f"# median of {name} ({len(members)} runs), wall ({unit}) "
                  "per layer: " + ", ".join(f"{v:.2f}" for v in groups[name]))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4))
    for label, starts, ends, costs, _ in runs:
        if medians:
            ax.plot(range(1, len(costs) + 1), costs, lw=0.6, alpha=0.5,
                    color="C0" if label.startswith("without") else "C1")
        else:
            ax.plot(range(1, len(costs) + 1), costs, marker="o", label=label)
    for k, (name, values) in enumerate(groups.items()):
        ax.plot(range(1, len(values) + 1), values, marker="o", lw=2,
                color="C0" if name.startswith("without") else
                ("C1" if name.startswith("with") else f"C{k + 2}"),
                label=f"{name} (median)")
    ax.set_xlabel("layer")
    ax.set_ylabel("wall time of the layer per 100 us simulated (s)"
                  if per_time else "wall time of the layer (s)")
    ax.set_xticks(range(1, max(len(r[3]) for r in runs) + 1))
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
