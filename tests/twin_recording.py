"""A lab recording made from a simulation, for twin experiments of the one-path commands: the
result's 37 markers renamed M01..M37 (so that nothing is matched by name), four head markers on a
headband, everything in a z-up lab frame in mm, with head motion, gaps and noise, at 100 Hz, as
C3D; and a 0.5-s rest recording of the same markers."""

from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline

from facemech import read_results
from facemech.io.markers import write_markers
from facemech.markerset import MarkerSet

#: model (x left, y up, z forward) -> lab (X forward, Y left, Z up), as a Vicon lab often is
MODEL_TO_LAB = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
LAB_OFFSET_M = np.array([0.35, -0.12, 1.45])  # the head somewhere in the capture volume


def _rot(axis: int, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    i, j = [k for k in range(3) if k != axis]
    r = np.eye(3)
    r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
    return r


def head_motion(time: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-frame rotation (frames, 3, 3) and translation (frames, 3), m, of a nodding head:
    up to 4 degrees of pitch, 2.5 of yaw, 5 mm of translation."""
    pitch = np.deg2rad(4.0) * np.sin(2 * np.pi * 0.45 * time + 0.3)
    yaw = np.deg2rad(2.5) * np.sin(2 * np.pi * 0.3 * time + 1.0)
    rot = np.array([_rot(0, p) @ _rot(1, y) for p, y in zip(pitch, yaw, strict=True)])
    trans = np.stack([0.003 * np.sin(2 * np.pi * 0.2 * time), 0.005 * np.sin(
        2 * np.pi * 0.35 * time + 0.5), 0.002 * np.cos(2 * np.pi * 0.25 * time)], axis=1)
    return rot, trans


def headband(rest_skin: np.ndarray) -> np.ndarray:
    """Four head-marker positions (4, 3), m, 15 mm in front of the skin: forehead left, centre
    and right on a headband, and the bridge of the nose (as on glasses), so that they span the
    head's three axes."""
    top = rest_skin[:, 1].max()
    band = rest_skin[rest_skin[:, 1] > top - 0.06]
    picks = [band[np.argmin(np.abs(band[:, 0] - x) + np.abs(band[:, 1] - (top - y)))]
             for x, y in ((-0.045, 0.015), (0.0, 0.005), (0.045, 0.015), (0.0, 0.045))]
    return np.array(picks) + np.array([0.0, 0.0, 0.015])


def to_lab(model_m: np.ndarray, time: np.ndarray, pivot: np.ndarray) -> np.ndarray:
    """Model-frame positions (frames, n, 3) -> the moving head in the lab frame, metres."""
    rot, trans = head_motion(time)
    moved = np.einsum("fij,fnj->fni", rot, model_m - pivot) + pivot + trans[:, None]
    return moved @ MODEL_TO_LAB.T + LAB_OFFSET_M


def lab_recordings(result_path, folder, *, rate: float = 100.0, noise_m: float = 1e-4,
                   seed: int = 3) -> dict:
    """Write ``speech.c3d`` and ``rest.c3d`` into ``folder``; return their paths and the names
    of the renamed markers (``names[original] = "Mkk"``), head markers and frame markers."""
    ds = read_results(result_path)
    rng = np.random.default_rng(seed)
    skin = ds["markers"].values  # (frames, 37, 3), model frame, m
    keep = [k for k in range(skin.shape[1])  # a landmark and a marker can share a node
            if all(np.linalg.norm(skin[0, k] - skin[0, j]) > 1e-3 for j in range(k))]
    orig = [str(ds["marker"].values[k]) for k in keep]
    skin = skin[:, keep]
    names = {n: f"M{k + 1:02d}" for k, n in enumerate(orig)}
    t60 = ds["time"].values
    rest_skin = ds["rest_positions"].values if "rest_positions" in ds else skin[0]
    band = headband(np.asarray(rest_skin))
    pivot = np.array([0.0, -0.09, -0.08])  # about the upper neck
    out = {"names": names, "head": ("H1", "H2", "H3", "H4")}
    all_names = tuple(names[n] for n in orig) + out["head"]
    for label, duration in (("speech", t60[-1]), ("rest", 0.5)):
        t = np.arange(0.0, duration + 1e-9, 1.0 / rate)
        face = (CubicSpline(t60, skin, axis=0)(t) if label == "speech"
                else np.repeat(skin[:1], len(t), axis=0))
        pts = np.concatenate([face, np.repeat(band[None], len(t), axis=0)], axis=1)
        lab = to_lab(pts, t + (0.0 if label == "speech" else 7.0), pivot)
        lab += rng.normal(0.0, noise_m, lab.shape)
        if label == "speech":  # gaps: 7 and 5 frames of two lip markers, 3 of a head marker
            lab[30:37, orig.index("R05")] = np.nan
            lab[100:105, orig.index("L03")] = np.nan
            lab[60:63, len(orig) + 1] = np.nan
        path = folder / f"{label}.c3d"
        write_markers(path, MarkerSet(lab, all_names, rate, t), units="mm")
        out[label] = path
    out["frame"] = (names["mouth_corner_right"], names["mouth_corner_left"], names["stomion"])
    out["chin"] = names["R01"]
    return out
