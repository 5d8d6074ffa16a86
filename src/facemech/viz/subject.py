"""The picture of a subject folder: its face and markers, front and side, to check by eye that
every marker sits on the skin where it was placed."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .plots import save_figure, subplots


def subject_figure(path: str | Path, model, markers_m: np.ndarray, names, mapping: dict,
                   head=()) -> Path:
    """PNG: the face's epidermal nodes (grey) with the markers (model frame, metres; red on the
    skin, blue for head markers) and their nodes (black rings), front (x, y) and side (z, y).

    Parameters
    ----------
    model : the subject's face
    markers_m : (markers, 3) rest positions in the model's frame, metres
    names : the markers' names; ``mapping`` marker -> node; ``head`` the head markers
    """
    skin = model.rest_positions[: model.n_surface] * 1e3
    pts = np.asarray(markers_m) * 1e3
    fig, axes = subplots(1, 2, figsize=(11, 6.2))
    for ax, (i, j), label in zip(axes, ((0, 1), (2, 1)), ("front: x (left) mm", "side: z "
                                                           "(forward) mm"), strict=True):
        ax.scatter(skin[:, i], skin[:, j], s=1.5, c="0.75", lw=0)
        for k, n in enumerate(names):
            is_head = n in head
            ax.scatter(pts[k, i], pts[k, j], s=14, c="tab:blue" if is_head else "tab:red",
                       zorder=3)
            if n in mapping:
                node = skin[mapping[n]]
                ax.scatter(node[i], node[j], s=40, facecolors="none", edgecolors="k", lw=0.6,
                           zorder=2)
            if i == 0:
                ax.annotate(n, pts[k, [i, j]], fontsize=6, xytext=(2, 2),
                            textcoords="offset points")
        ax.set_aspect("equal")
        ax.set_xlabel(label)
        ax.set_ylabel("y (up) mm")
    return save_figure(fig, path, f"{model.name}: {len(mapping)} markers on the skin (red), "
                       f"their nodes (rings), head markers (blue)")


def landmarks_figure(path: str | Path, vertices: np.ndarray, positions: dict,
                     confidence: dict, generic_to_scan, *, title: str = "") -> Path:
    """PNG of a scan (grey points, front and side as the registration found them) with its
    landmarks coloured by confidence (green 1 to red 0) and named.

    Parameters
    ----------
    vertices : (n, 3) the scan, metres; ``positions`` name -> (3,) on it
    generic_to_scan : the registration's similarity; its inverse turns the scan to the front
    """
    from matplotlib import colormaps

    rot = generic_to_scan.rotation
    to_front = lambda p: (np.asarray(p) - generic_to_scan.translation) @ rot  # noqa: E731
    v = to_front(vertices) * 1e3
    names = list(positions)
    p = to_front(np.array([positions[n] for n in names])) * 1e3
    colour = colormaps["RdYlGn"](np.array([confidence[n] for n in names]))
    fig, axes = subplots(1, 2, figsize=(11, 6.2))
    step = max(1, len(v) // 20000)
    for ax, (i, j), label in zip(axes, ((0, 1), (2, 1)), ("front: x mm", "side: z mm"),
                                 strict=True):
        ax.scatter(v[::step, i], v[::step, j], s=1, c="0.75", lw=0)
        ax.scatter(p[:, i], p[:, j], s=28, c=colour, edgecolors="k", lw=0.5, zorder=3)
        if i == 0:
            for k, n in enumerate(names):
                ax.annotate(n, p[k, [i, j]], fontsize=6, xytext=(3, 2),
                            textcoords="offset points")
        ax.set_aspect("equal")
        ax.set_xlabel(label)
        ax.set_ylabel("y mm")
    return save_figure(fig, path, title)
