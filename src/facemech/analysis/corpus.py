"""An embedded corpus for the region analysis: 57 virtual markers, synthetic utterances.

The 57 sites follow the layout of Lucero & Munhall (2008), Fig. 1 (forehead, brows, eyelids,
nose, cheeks, lips, chin and jaw line); frontal (x, y) in mm on the generic face, origin at the
nasion, x < 0 the subject's right. Utterances are random strings of CV syllables whose muscle
activity and jaw motion are drawn per syllable, simulated with the seeds' physical model (the
``lucero1999`` preset on the uniform tissue, explicit Euler at dt = 1 ms, which the forward
benchmark places within 0.2 mm of the paper's 0.33 ms at the markers). Measurement noise
(0.5 mm, Gaussian, per coordinate) is added afterwards.
``copied_eyelid=True`` reproduces the seed's artifact: the left upper eyelid marker's
displacement is copied from the right upper eyelid's.

The simulated (noise-free) trajectories are cached in ``$XDG_CACHE_HOME/facemech`` (or
``~/.cache/facemech``), keyed by the corpus settings and the facemech version.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..params import MUSCLE_GROUPS, Parameters
from ..waveforms import cosine_bump

# name: (x, y) mm; the seeds number markers from the top of the face down
SITES: dict[str, tuple[float, float]] = {
    "forehead_R2": (-40, 55), "forehead_R1": (-20, 58), "forehead_C": (0, 60),
    "forehead_L1": (20, 58), "forehead_L2": (40, 55),
    "temple_R": (-55, 0), "temple_L": (55, 0),
    "brow_R3": (-45, 12), "brow_R2": (-30, 15), "brow_R1": (-15, 14),
    "brow_L1": (15, 14), "brow_L2": (30, 15), "brow_L3": (45, 12),
    "eyelid_upper_R": (-32, 2), "eyelid_upper_L": (32, 2),
    "eyelid_lower_R": (-32, -10), "eyelid_lower_L": (32, -10),
    "nose_bridge": (0, -15), "nose_tip": (0, -40), "ala_R": (-15, -47), "ala_L": (15, -47),
    "cheek_upper_R2": (-45, -30), "cheek_upper_R1": (-30, -33),
    "cheek_upper_L1": (30, -33), "cheek_upper_L2": (45, -30),
    "cheek_mid_R2": (-50, -55), "cheek_mid_R1": (-38, -60),
    "cheek_mid_L1": (38, -60), "cheek_mid_L2": (50, -55),
    "nasolabial_R": (-22, -58), "nasolabial_L": (22, -58),
    "upper_lip_R2": (-17, -68), "upper_lip_R1": (-9, -65), "upper_lip_C": (0, -64),
    "upper_lip_L1": (9, -65), "upper_lip_L2": (17, -68),
    "corner_R": (-26, -73), "corner_L": (26, -73),
    "lower_lip_R2": (-17, -78), "lower_lip_R1": (-9, -81), "lower_lip_C": (0, -82),
    "lower_lip_L1": (9, -81), "lower_lip_L2": (17, -78),
    "cheek_low_R": (-38, -85), "cheek_low_L": (38, -85),
    "chin_upper_R": (-14, -98), "chin_upper_C": (0, -100), "chin_upper_L": (14, -98),
    "chin_R": (-18, -110), "chin_C": (0, -112), "chin_L": (18, -110),
    "jaw_R2": (-48, -80), "jaw_R1": (-40, -95), "jaw_low_R": (-30, -118),
    "jaw_low_L": (30, -118), "jaw_L1": (40, -95), "jaw_L2": (48, -80),
}
COPY_TARGET, COPY_SOURCE = "eyelid_upper_L", "eyelid_upper_R"

NOISE = 0.5e-3  #: m, measurement noise per coordinate (the seed's Vicon precision)


def site_nodes(face) -> dict[str, int]:
    """Epidermal node of each of the 57 sites on the built-in face (upper or lower lip kept)."""
    from ..geometry import generic

    xy = np.array(list(SITES.values()), float)
    pts = generic.surface_point(xy[:, 0], xy[:, 1]) * 1e-3
    v = face.rest_positions[: face.n_surface]
    lower = set(face.lip_pairs[:, 1].tolist())
    out = {}
    for name, p, (_, y) in zip(SITES, pts, xy, strict=True):
        order = np.argsort(np.linalg.norm(v - p, axis=1))
        for node in order[:6]:
            is_lower = node in lower or v[node, 1] < generic.Y_STOMION * 1e-3
            if (y < generic.Y_STOMION) == is_lower or abs(y - generic.Y_STOMION) < 1:
                out[name] = int(node)
                break
        else:
            out[name] = int(order[0])
    return out


def random_utterance(rng: np.random.Generator, frames: int,
                     frame_rate: float = Parameters.frame_rate):
    """Activity (frames, groups) and jaw angles (frames,) rad of a random CV-syllable string at
    ``frame_rate`` (Hz)."""
    t = np.arange(frames) / frame_rate
    act = np.zeros((frames, len(MUSCLE_GROUPS)))
    jaw = np.zeros(frames)
    period = rng.uniform(0.18, 0.32)
    onset = rng.uniform(0.0, 0.1)
    lower_face = ["DAO", "DLI", "LAO", "ZYG", "LLS", "MEN", "OOS", "OOI", "ZMI", "RIS", "LLSAN"]
    upper_face = ["COR", "CSU", "FRM", "FRL", "FRI"]
    while onset < t[-1]:
        width = period * rng.uniform(0.8, 1.4)
        bump = cosine_bump(t, onset + width / 2, width)
        jaw += np.radians(rng.uniform(0.0, 10.0)) * bump
        for g in rng.choice(lower_face, size=rng.integers(1, 5), replace=False):
            act[:, MUSCLE_GROUPS.index(g)] += rng.uniform(0.1, 0.9) * bump
        if rng.random() < 0.3:
            g = rng.choice(upper_face)
            act[:, MUSCLE_GROUPS.index(g)] += rng.uniform(0.1, 0.8) * bump
        onset += period
    return np.clip(act, 0, 1), jaw


@dataclass(frozen=True)
class Corpus:
    """Utterances (each (frames, 57, 3), metres, noise added), names, sites' nodes."""

    utterances: list
    names: tuple[str, ...]
    nodes: dict
    rate: float
    noise: float
    copied_eyelid: bool


def _cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "facemech"


def simulate_corpus(n_utterances: int = 40, frames: int = 60, seed: int = 2008,
                    progress: Callable[[int, int], None] | None = None,
                    cache: bool = True) -> list[np.ndarray]:
    """Noise-free trajectories of the 57 sites for ``n_utterances`` random utterances."""
    from .._version import __version__
    from ..geometry.builder import default_face
    from ..solvers.forward import simulate

    key = json.dumps({"n": n_utterances, "frames": frames, "seed": seed, "v": __version__,
                      "sites": SITES}, sort_keys=True)
    digest = hashlib.sha256(key.encode()).hexdigest()[:16]
    path = _cache_dir() / f"corpus-{digest}.npz"
    if cache and path.is_file():
        with np.load(path) as z:
            return [z[f"u{k}"] for k in range(n_utterances)]
    from ..physics.model import model

    seeds = model(default_face(tissue="uniform"), "lucero1999")
    face = seeds.face
    nodes = site_nodes(face)
    idx = np.array([nodes[n] for n in SITES])
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n_utterances):
        act, jaw = random_utterance(rng, frames, seeds.params.frame_rate)
        sim = simulate(seeds, act, jaw, integrator="euler", dt=1e-3)
        out.append(sim.positions[:, idx])
        if progress is not None:
            progress(k + 1, n_utterances)
    if cache:
        from ..atomic import atomic_path

        with atomic_path(path, suffix=".npz") as tmp, open(tmp, "wb") as fh:
            np.savez_compressed(fh, **{f"u{k}": u for k, u in enumerate(out)})
    return out


def embedded_corpus(n_utterances: int = 40, frames: int = 60, *, noise: float = NOISE,
                    copied_eyelid: bool = True, seed: int = 2008,
                    progress: Callable[[int, int], None] | None = None,
                    cache: bool = True) -> Corpus:
    """The embedded corpus: simulated trajectories plus measurement noise (and the artifact)."""
    from ..geometry.builder import default_face
    from ..params import preset

    clean = simulate_corpus(n_utterances, frames, seed, progress, cache)
    rng = np.random.default_rng(seed + 1)
    names = tuple(SITES)
    utts = []
    tgt, src = names.index(COPY_TARGET), names.index(COPY_SOURCE)
    for u in clean:
        x = u + rng.normal(0.0, noise, u.shape)
        if copied_eyelid:
            x[:, tgt] = x[:, src] - x[0, src] + x[0, tgt]  # the same displacement
        utts.append(x)
    return Corpus(utts, names, site_nodes(default_face()), preset("lucero1999").frame_rate, noise,
                  copied_eyelid)
