"""Panels of an inversion's figure: a control, a combination of controls, and each sensor's
model against measured trajectory (:func:`facemech.viz.plots.inversion_figure`)."""

from __future__ import annotations

import numpy as np

from ..kinematics.stats import cross_correlation

#: m: an axis along which a sensor's data vary less than this gets no panel
STILL_M = 1e-9


def control_panel(ax, time, control, name, *, lo, se, truth, seen):
    """One control over time (the last frame left out: it repeats the one before), with a band
    of +-2 SE, the truth dashed if known, grey and labelled "regularised" if not determined."""
    t = time[:-1]
    scale = np.degrees(0.1) if name == "jaw" else 1.0
    y = control[:-1] * scale
    if se is not None:
        band = 2.0 * np.nan_to_num(se[:-1], nan=0.0, posinf=10.0) * scale
        ax.fill_between(t, y - band, y + band, color="tab:blue" if seen else "0.85",
                        alpha=0.35, lw=0, label="+-2 SE")
    ax.plot(t, y, "-", color="k" if seen else "0.6", lw=1.3, label="inverted")
    if truth is not None:
        ax.plot(t, truth[:-1] * scale, "k--", lw=1.0, label="true")
        ax.set_title(f"r = {cross_correlation(control[:-1], truth[:-1]):.2f}",
                     fontsize=7, loc="right", pad=1)
    if not seen:
        ax.text(0.01, 0.85, "regularised: not determined by the markers alone",
                transform=ax.transAxes, fontsize=7, color="0.4", va="top")
    if name == "jaw":
        top = float(np.max(y)) if len(t) else 1.0
        ax.set_ylim(min(-1.0, float(np.min(y))) - 0.5, max(top, 2.0) * 1.15)
        ax.set_ylabel("jaw\n(deg)", rotation=0, ha="right", fontsize=8)
    else:
        ax.set_ylim(lo - 0.05, 1.05)
        ax.set_ylabel(name, rotation=0, ha="right", fontsize=8)
    ax.tick_params(labelsize=7)


def combination_panel(ax, time, combo, controls, names, noise_mm):
    """A combination of controls the markers measure, with +-2 SE at ``noise_mm``."""
    t = time[:-1]
    v = combo.of(controls, names)[:-1]
    band = 2.0 * combo.se(max(float(noise_mm), 0.1))
    ax.fill_between(t, v - band, v + band, color="tab:green", alpha=0.3, lw=0, label="+-2 SE")
    ax.plot(t, v, "-", color="darkgreen", lw=1.3, label="combination")
    ax.text(0.01, 0.85, f"measured: {combo.name}" + ("" if combo.determined(noise_mm)
                                                     else " (SE over 0.1 at this noise)"),
            transform=ax.transAxes, fontsize=7, color="darkgreen", va="top")
    ax.set_ylabel(f"comb.\n{combo.lead}", rotation=0, ha="right", fontsize=8)
    ax.tick_params(labelsize=7)


def sensor_panels(axes, time, names, model, measured) -> int:
    """Draw, per sensor and axis its data vary along, the model (solid) against the measured
    (dashed) displacement from the first frame (mm), with a legend and the fit in the title;
    return the number of panels (``axes`` None: only count them)."""
    model, measured = np.asarray(model, float), np.asarray(measured, float)
    pairs = [(j, a) for j in range(len(names)) for a in range(3)
             if np.nanmax(measured[:, j, a]) - np.nanmin(measured[:, j, a]) > STILL_M]
    if axes is None:
        return len(pairs)
    for ax, (j, a) in zip(axes, pairs, strict=True):
        d = (measured[:, j, a] - measured[0, j, a]) * 1e3
        m = (model[:, j, a] - measured[0, j, a]) * 1e3
        ok = np.isfinite(d) & np.isfinite(m)
        ax.plot(time, d, "--", color="tab:red", lw=1.0, label="measured")
        ax.plot(time, m, "-", color="k", lw=1.2, label="model")
        diff = m[ok] - d[ok]
        rms = float(np.sqrt(np.mean(diff ** 2))) if ok.any() else float("nan")
        r = cross_correlation(m[ok], d[ok]) if ok.sum() > 2 else float("nan")
        ax.set_title(f"{names[j]} {'xyz'[a]}: RMS {rms:.2f} mm, r {r:.2f}", fontsize=7,
                     loc="right", pad=1)
        ax.set_ylabel(f"{names[j]} {'xyz'[a]}\n(mm)", rotation=0, ha="right", fontsize=8)
        ax.legend(fontsize=6, loc="upper left", frameon=False, ncol=2)
        ax.tick_params(labelsize=7)
    return len(pairs)
