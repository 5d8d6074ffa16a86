"""Draw docs/img/creep-section.png: the tissue's midsagittal section at rest and after 1.5 s
of a full, held lip gesture, coloured by each prism's volume ratio J = V / V0 (issue 27's creep,
docs/model.md).

``python tools/creep_figure.py [-o docs/img/creep-section.png]`` (about a minute).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from facemech.physics.model import model as face_model

#: (title, groups, parameter changes) of each panel after the rest
PANELS = (
    ("full LLS, 1.5 s\n(the anatomical preset)", ("LLS",), {}),
    ("full LLS, 1.5 s\nvolume floor 0.5, stiffening 4", ("LLS",),
     {"volume_floor": 0.5, "volume_floor_modulus": 1e6, "stiffening": 4.0}),
    ("full DLI, 1.5 s\nvolume floor 0.5, stiffening 4", ("DLI",),
     {"volume_floor": 0.5, "volume_floor_modulus": 1e6, "stiffening": 4.0}),
)
HALF_WIDTH = 3e-3  #: m, the slab about the midline that is drawn


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-o", "--output", type=Path,
                    default=Path(__file__).resolve().parent.parent / "docs/img/creep-section.png")
    args = ap.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from threadpoolctl import threadpool_limits

    from facemech import default_face
    from facemech.geometry.builder import for_tissue
    from facemech.geometry.prism import rest_geometry
    from facemech.params import MUSCLE_GROUPS, preset
    from facemech.solvers.forward import simulate

    base = preset("anatomical")
    face = for_tissue(default_face("default"), base.tissue)
    x0 = face.rest_positions
    v0 = rest_geometry(x0, face.prism_nodes, symmetric=True)[0]
    i, j = face.spring_i, face.spring_j
    springs = (np.abs(x0[i, 0]) < HALF_WIDTH) & (np.abs(x0[j, 0]) < HALF_WIDTH) & \
        (x0[i, 1] < -0.03)
    centre = x0[face.prism_nodes].mean(axis=1)
    prisms = (np.abs(centre[:, 0]) < HALF_WIDTH) & (centre[:, 1] < -0.03)
    fig, axes = plt.subplots(1, len(PANELS) + 1, figsize=(3.3 * (len(PANELS) + 1), 4.6),
                             sharex=True, sharey=True)

    def draw(ax, x, title, ratio=None):
        seg = np.stack([x[i[springs]][:, [2, 1]], x[j[springs]][:, [2, 1]]], axis=1) * 1e3
        from matplotlib.collections import LineCollection

        ax.add_collection(LineCollection(seg, colors="k", linewidths=0.3))
        if ratio is not None:
            c = x[face.prism_nodes[prisms]].mean(axis=1) * 1e3
            sc = ax.scatter(c[:, 2], c[:, 1], c=ratio[prisms], cmap="RdYlGn", vmin=0.0,
                            vmax=1.2, s=10, zorder=3)
            ax.set_title(f"{title}\nsmallest J {ratio[prisms].min():.2f}", fontsize=9)
            return sc
        ax.set_title(title, fontsize=9)
        return None

    draw(axes[0], x0, "rest")
    frames = int(round(1.5 * base.frame_rate)) + 1
    sc = None
    for ax, (title, groups, changes) in zip(axes[1:], PANELS, strict=True):
        act = np.zeros((frames, len(MUSCLE_GROUPS)))
        for g in groups:
            act[:, MUSCLE_GROUPS.index(g)] = 1.0
        with threadpool_limits(1):
            sim = simulate(face_model(face, base.with_(**changes)), act)
        x = sim.final_state.positions
        ratio = rest_geometry(x, face.prism_nodes, symmetric=True)[0] / v0
        sc = draw(ax, x, title, ratio)
    for ax in axes:
        ax.set_aspect("equal")
        ax.set_xlabel("z, forward (mm)")
        ax.autoscale_view()
    axes[0].set_ylabel("y (mm)")
    fig.colorbar(sc, ax=axes, shrink=0.8, label="volume ratio J = V / V0")
    args.output.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.output, dpi=90, bbox_inches="tight")
    print(args.output)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
