"""Figures of the region analysis (Lucero & Munhall 2008, Figs. 2-7, 9, 10)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from .plots import subplots


def _save(fig, path):
    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, dpi=110)
    return Path(path)


def r_values_figure(path, r_values_mm: np.ndarray, eps_mm: float, title: str = ""):
    """Fig. 2: normalised R values against pivot order, with the epsilon line."""
    fig, ax = subplots(figsize=(6, 3.6))
    k = np.arange(1, len(r_values_mm) + 1)
    ax.semilogy(k, np.maximum(r_values_mm, 1e-6), "ko", ms=3)
    ax.axhline(eps_mm, color="0.5", ls="--", lw=1, label=f"epsilon = {eps_mm:.2f} mm")
    ax.set_xlabel("pivot (marker in selection order)")
    ax.set_ylabel("normalised |r_kk| (mm)")
    ax.legend(fontsize=8)
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return _save(fig, path)


def stability_figure(path, counts, first_r_mm: np.ndarray):
    """Fig. 3: the first R values against the number of utterances used."""
    fig, ax = subplots(figsize=(6, 3.6))
    for j in range(first_r_mm.shape[1]):
        ax.plot(counts, first_r_mm[:, j], "-o", ms=2, lw=1)
    ax.set_xlabel("number of utterances")
    ax.set_ylabel("normalised R value (mm)")
    fig.tight_layout()
    return _save(fig, path)


def region_maps(path, xy_mm: np.ndarray, maps: list[np.ndarray], titles: list[str],
                marks: list[int] | None = None, xlabel: str = "x (mm)"):
    """Signed maps (Figs. 4-7): values at markers interpolated (cubic) over the frontal plane."""
    from scipy.interpolate import griddata

    n = len(maps)
    fig, axes = subplots(1, n, figsize=(3.2 * n, 4.0), squeeze=False)
    gx, gy = np.meshgrid(np.linspace(xy_mm[:, 0].min(), xy_mm[:, 0].max(), 120),
                         np.linspace(xy_mm[:, 1].min(), xy_mm[:, 1].max(), 160))
    for ax, vals, title, mark in zip(axes[0], maps, titles, marks or [None] * n, strict=True):
        grid = griddata(xy_mm, vals, (gx, gy), method="cubic")
        lim = max(np.nanmax(np.abs(vals)), 1e-9)
        im = ax.contourf(gx, gy, grid, levels=np.linspace(-lim, lim, 21), cmap="RdBu_r")
        ax.scatter(xy_mm[:, 0], xy_mm[:, 1], c="k", s=6)
        if mark is not None:
            ax.scatter(*xy_mm[mark], marker="*", c="gold", s=120, edgecolors="k")
        ax.set_aspect("equal")
        ax.set_title(title, fontsize=9)
        ax.set_xlabel(xlabel)
        fig.colorbar(im, ax=ax, shrink=0.7)
    fig.tight_layout()
    return _save(fig, path)


def error_figure(path, ks, abs_mm, rel, pca_mm):
    """Fig. 10: mean absolute and relative error of the secondary markers against k."""
    fig, axes = subplots(2, 1, figsize=(6, 5), sharex=True)
    axes[0].plot(ks, abs_mm, "ko-", ms=3, label="independent markers (QR)")
    axes[0].plot(ks, pca_mm, "s--", color="0.5", ms=3, label="PCA, same k (all markers seen)")
    axes[0].set_ylabel("mean abs. error (mm)")
    axes[0].legend(fontsize=8)
    axes[1].plot(ks, rel, "ko-", ms=3)
    axes[1].set_ylabel("relative error")
    axes[1].set_xlabel("k (markers in the basis)")
    fig.tight_layout()
    return _save(fig, path)


def trajectory_figure(path, time, recorded_mm, predicted_mm, title):
    """Fig. 9: one marker's trajectory, recorded (dashed) and predicted (full), x, y, z."""
    fig, axes = subplots(3, 1, figsize=(6, 5), sharex=True)
    for a, ax in enumerate(axes):
        ax.plot(time, predicted_mm[:, a], "k-", lw=1.2, label="model")
        ax.plot(time, recorded_mm[:, a], "k--", lw=1.0, label="recorded")
        ax.set_ylabel(f"{'xyz'[a]} (mm)")
    axes[0].legend(fontsize=8)
    axes[0].set_title(title, fontsize=9)
    axes[-1].set_xlabel("time (s)")
    fig.tight_layout()
    return _save(fig, path)
