#!/usr/bin/env python3
"""Error against sample points on the room's teapot, uniform placement against parallax (and
adaptive, where given): the mirror mode, and pbr at roughness 0.3 shaded per point, per
direction and, where given, per point visible and per point searched. Means over seeds, each seed's figure a faint dot
(docs/measurements.md, "Points on the room's teapot").

    python3 scripts/teapot-points-plot.py TABLE.txt OUT.png

TABLE.txt: one line per store, `PLACEMENT-N-SEED POINTS BAKE_S STORE_MB MIRROR PBR_PER_POINT
PBR_PER_DIRECTION [PBR_PER_POINT_VISIBLE [PBR_PER_POINT_SEARCHED]]` (RMSE L*, whitespace
separated); a placement's curve of an optional column is drawn where every one of its lines has
the column. Needs matplotlib.
"""
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import NullFormatter, ScalarFormatter  # noqa: E402


# The placements, in legend order, and their colours.
PLACEMENTS = {"uniform": "tab:blue", "parallax": "tab:red", "adaptive": "tab:green"}


def read(path):
    """(placement, N) -> [(points, mirror, per point, per direction, per point visible or
    None, per point searched or None)], and the seeds read."""
    runs = defaultdict(list)
    seeds = set()
    for number, line in enumerate(open(path), 1):
        f = line.split()
        if not f:
            continue
        try:
            placement, n, seed = f[0].split("-")
            if placement not in PLACEMENTS:
                raise ValueError(placement)
            if len(f) > 9:
                raise ValueError(f[9])
            optional = [float(v) for v in f[7:]] + [None] * (9 - max(len(f), 7))
            runs[(placement, int(n))].append(
                (int(f[1]), float(f[4]), float(f[5]), float(f[6]), *optional)
            )
            seeds.add(int(seed))
        except (ValueError, IndexError):
            sys.exit(f"{path}:{number}: expected PLACEMENT-N-SEED POINTS BAKE MB MIRROR PP PD [PPV [PPS]]"
                     f" (PLACEMENT one of {', '.join(PLACEMENTS)})")
    return runs, seeds


def curve(ax, runs, placement, column, dash, label):
    colour = PLACEMENTS[placement]
    xs, ys = [], []
    for key in sorted(k for k in runs if k[0] == placement):
        px = [r[0] for r in runs[key]]
        py = [r[column] for r in runs[key]]
        ax.scatter(px, py, s=9, color=colour, alpha=0.35)
        xs.append(sum(px) / len(px))
        ys.append(sum(py) / len(py))
    ax.plot(xs, ys, dash, marker="o", color=colour, label=label)


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    runs, seeds = read(sys.argv[1])
    fig, (mirror, pbr) = plt.subplots(1, 2, figsize=(11, 4.6), dpi=110)
    for placement in sorted({k[0] for k in runs}, key=list(PLACEMENTS).index):
        curve(mirror, runs, placement, 1, "-", placement)
        curve(pbr, runs, placement, 2, "--", f"{placement}, per point (default)")
        curve(pbr, runs, placement, 3, "-", f"{placement}, per direction")
        for column, dash, name in [(4, ":", "per point visible"), (5, "-.", "per point searched")]:
            if all(r[column] is not None for k in runs if k[0] == placement for r in runs[k]):
                curve(pbr, runs, placement, column, dash, f"{placement}, {name}")
    mirror.set_title("mirror")
    pbr.set_title("pbr, metallic 1, roughness 0.3, M = 16")
    for ax in (mirror, pbr):
        ax.set_xscale("log")
        ax.set_xticks([250, 350, 500, 700, 1000, 1300])
        ax.xaxis.set_major_formatter(ScalarFormatter())
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("sample points (after refinement)")
        ax.set_ylabel("RMSE L* against the truth")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    seed_list = ", ".join(str(s) for s in sorted(seeds))
    fig.suptitle(f"The room's teapot at 16 samples per texel, denoised: means of seeds {seed_list}")
    fig.tight_layout()
    fig.savefig(sys.argv[2])


main()
