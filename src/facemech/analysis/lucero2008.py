"""Region analysis runs: on user files (``facemech regions``) and on the embedded corpus
(``facemech experiment lucero2008``), with the seed's figures and numbers beside ours."""

from __future__ import annotations

import json
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from ..errors import InputError
from .regions import IndependentMarkers

#: What Lucero & Munhall (2008) report for subject S1, to print beside our numbers.
PAPER = {
    "rank": 56,
    "r_56_mm": 22.70,
    "r_57_mm": 0.10,
    "copied_marker_selected": "last (marker 13, left upper eyelid)",
    "first_selected": "lower lip centre (marker 40), then the left lip corner (34)",
    "stable_after_utterances": 25,
    "jaw_marker_max_error_k10_mm": [0.8, 2.0, 0.9],
}


def _write_json(path: Path, data: dict) -> None:
    from ..io.atomic import atomic_path

    with atomic_path(path, suffix=".json") as tmp:
        tmp.write_text(json.dumps(data, indent=2))


def analyse(utterances: Sequence[np.ndarray], names: Sequence[str], out_dir: str | Path, *,
            k: int | None = None, eps: float | None = None, method: str = "qrcp",
            train: Sequence[int] | None = None, test: Sequence[int] | None = None,
            neutral: str | np.ndarray = "first", rate: float = 60.0,
            k_values: Sequence[int] | None = None,
            trajectory_marker: str | Sequence[str] | None = None,
            stability: bool = True) -> dict:
    """Fit, evaluate and draw the region analysis; write ``summary.json`` and PNG figures.

    Utterances are (frames, markers, 3) arrays in metres; numbers in the summary are in mm.
    """
    from ..viz import regions as fig

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    n_utt = len(utterances)
    train = list(range(n_utt)) if train is None else list(train)
    test = [] if test is None else list(test)
    for i in (*train, *test):
        if not 0 <= i < n_utt:
            raise InputError(f"utterance {i + 1} does not exist (have {n_utt})",
                             field="train/test")
    tr = [utterances[i] for i in train]
    te = [utterances[i] for i in test]
    full = IndependentMarkers(eps=eps, neutral=neutral).fit(tr)
    kk = k if k is not None else max(1, min(full.rank_, 10))
    with warnings.catch_warnings():  # k above the epsilon-rank is reported in the summary
        warnings.simplefilter("ignore", UserWarning)
        model = IndependentMarkers(k=kk, eps=full.eps_, method=method, neutral=neutral).fit(tr)
        qrcp = model if method == "qrcp" else IndependentMarkers(k=kk, eps=full.eps_).fit(tr)
    names = list(names)
    summary: dict = {
        "utterances": n_utt, "train": [i + 1 for i in train], "test": [i + 1 for i in test],
        "markers": len(names), "eps_mm": full.eps_ * 1e3, "rank": full.rank_, "k": kk,
        "method": method, "k_exceeds_rank": bool(kk > full.rank_),
        "order": [names[i] for i in full.order_],
        "r_values_mm": (full.r_values_ * 1e3).tolist(),
        "selected": [names[i] for i in model.selected_],
        "residual_R22_F_mm": model.residual_ * 1e3,
        "max_abs_coefficient": float(np.abs(model.coef_).max()) if model.coef_.size else 0.0,
        "max_abs_coefficient_qrcp": float(np.abs(qrcp.coef_).max()) if qrcp.coef_.size else 0.0,
        "strong_rrqr_swaps": int(getattr(model, "swaps_", 0)),
    }
    figures = {}
    figures["r_values"] = str(fig.r_values_figure(out / "r_values.png", full.r_values_ * 1e3,
                                                  full.eps_ * 1e3, "R values (Fig. 2)").name)
    rest = np.asarray(tr[0][0] if isinstance(neutral, str) else neutral) * 1e3
    xy = rest[:, :2]
    maps, titles, marks = [], [], []
    for j in range(min(3, kk)):
        vals = np.zeros(len(names))
        vals[model.secondary_] = model.coef_[j]
        vals[model.selected_[j]] = 1.0
        maps.append(vals)
        titles.append(f"eigenregion of {names[model.selected_[j]]}")
        marks.append(int(model.selected_[j]))
    if maps:
        figures["eigenregions"] = str(fig.region_maps(out / "eigenregions.png", xy, maps, titles,
                                                      marks).name)
    r = full.R_
    omaps, otitles, omarks = [], [], []
    for j in range(min(3, r.shape[0])):
        vals = np.zeros(len(names))
        vals[full.order_] = r[j] / r[j, j]
        omaps.append(vals)
        otitles.append(f"orthogonal region {j + 1} ({names[full.order_[j]]})")
        omarks.append(int(full.order_[j]))
    figures["orthogonal_regions"] = str(fig.region_maps(out / "orthogonal_regions.png", xy,
                                                        omaps, otitles, omarks).name)
    if te:
        ks = list(k_values) if k_values is not None else list(range(1, min(len(names) - 1,
                                                                             20) + 1))
        rows = []
        for kv in ks:
            e = full.with_k(kv).errors(te)  # one factorisation serves every k
            rows.append({"k": kv, "mean_abs_error_mm": e["mean_abs_error"] * 1e3,
                         "relative_error": e["relative_error"],
                         "pca_mean_abs_error_mm": e["pca_mean_abs_error"] * 1e3})
        summary["held_out_error"] = rows
        figures["errors"] = str(fig.error_figure(
            out / "errors.png", ks, [r_["mean_abs_error_mm"] for r_ in rows],
            [r_["relative_error"] for r_ in rows],
            [r_["pca_mean_abs_error_mm"] for r_ in rows]).name)
        secondary = [names[i] for i in model.secondary_]
        wanted = [trajectory_marker] if isinstance(trajectory_marker, str) else list(
            trajectory_marker or [])
        name = next((w for w in wanted if w in secondary), secondary[0])
        j = names.index(name)
        u = np.asarray(te[0])
        base = u[0] if isinstance(neutral, str) else neutral
        pred = model.predict((u - base)[:, model.selected_])[:, j] + base[j]
        t = np.arange(len(u)) / rate
        figures["trajectory"] = str(fig.trajectory_figure(
            out / "trajectory.png", t, u[:, j] * 1e3, pred * 1e3,
            f"{name}, held-out utterance {test[0] + 1}, k = {kk} (Fig. 9)").name)
        summary["trajectory"] = {"marker": name, "utterance": test[0] + 1,
                                 "max_error_xyz_mm": (np.abs(pred - u[:, j]).max(axis=0)
                                                      * 1e3).tolist()}
    if stability and len(tr) >= 10:
        counts = list(range(5, len(tr) + 1, 5))
        first = []
        for c in counts:
            m = IndependentMarkers(eps=full.eps_, neutral=neutral).fit(tr[:c])
            first.append(m.r_values_[:12] * 1e3)
        first = np.array(first)
        summary["stability"] = {"utterances": counts, "first_r_values_mm": first.tolist()}
        figures["stability"] = str(fig.stability_figure(out / "stability.png", counts,
                                                        first).name)
    summary["figures"] = figures
    _write_json(out / "summary.json", summary)
    summary["_model"] = model
    return summary


def insertion_distances(face, site_nodes: dict[str, int], selected: Sequence[str], *,
                        draws: int = 2000, seed: int = 0) -> dict:
    """How far the selected markers lie from the nearest muscle insertion, against random picks.

    Distances (mm) from each marker's rest position to the nearest insertion node (linear
    muscles) or sphincter path node of the face.
    """
    m = face.muscles
    ins = face.rest_positions[np.unique(m.nodes)]
    names = list(site_nodes)
    pos = face.rest_positions[[site_nodes[n] for n in names]]
    d = np.min(np.linalg.norm(pos[:, None] - ins[None], axis=2), axis=1) * 1e3
    sel = [names.index(n) for n in selected]
    rng = np.random.default_rng(seed)
    rand = np.array([d[rng.choice(len(names), len(sel), replace=False)].mean()
                     for _ in range(draws)])
    return {"selected_mean_mm": float(d[sel].mean()), "selected_mm": d[sel].tolist(),
            "random_mean_mm": float(rand.mean()),
            "random_p_value": float(np.mean(rand <= d[sel].mean()))}


def dense_animation(path, face, site_nodes: dict[str, int], displacements: np.ndarray,
                    progress: Callable[[int, int], None] | None = None) -> Path:
    """MP4 of the face surface moved by marker displacements (frames, 57, 3) m, interpolated
    over all epidermal nodes with a thin-plate spline on the rest positions."""
    from scipy.interpolate import RBFInterpolator

    from ..viz.movie import write_movie
    from ..viz.scene import build_scene, look_from_model

    names = list(site_nodes)
    rest = face.rest_positions[: face.n_surface]
    src = rest[[site_nodes[n] for n in names]]
    frames = []
    for d in displacements:
        rbf = RBFInterpolator(src, d, kernel="thin_plate_spline", smoothing=0.0)
        frames.append(rest + rbf(rest))
    return write_movie(path, build_scene(look_from_model(face)), np.array(frames),
                       progress=progress)


def run_lucero2008(out_dir: str | Path, *, n_utterances: int = 40, frames: int = 60,
                   k: int = 10, video: bool = True,
                   progress: Callable[[str, int, int], None] | None = None) -> dict:
    """The seed's analysis on the embedded corpus; writes figures, MP4 and summary.json."""
    from ..geometry.builder import default_face
    from .corpus import COPY_SOURCE, COPY_TARGET, embedded_corpus
    from .regions import noise_floor

    out = Path(out_dir)

    def step(stage):
        return None if progress is None else (lambda d, n: progress(stage, d, n))

    corpus = embedded_corpus(n_utterances, frames, progress=step("simulate corpus"))
    n_train = max(2, round(0.75 * n_utterances))
    s = analyse(corpus.utterances, corpus.names, out, k=k, train=range(n_train),
                test=range(n_train, n_utterances),
                trajectory_marker=("jaw_low_L", "jaw_low_R", "jaw_L1", "jaw_R1", "chin_L"))
    model = s.pop("_model")
    full_all = IndependentMarkers().fit(corpus.utterances)
    names = list(corpus.names)
    last = names[full_all.order_[-1]]
    r = full_all.r_values_ * 1e3
    s["all_utterances"] = {"rank": full_all.rank_, "last_selected": last,
                           "r_last_mm": float(r[-1]), "r_before_last_mm": float(r[-2]),
                           "noise_floor_mm": noise_floor(corpus.utterances) * 1e3}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        strong = IndependentMarkers(k=k, method="strong", bound=2.0).fit(
            corpus.utterances[:n_train])
    s["strong_rrqr"] = {"bound": 2.0, "max_abs_coefficient": float(np.abs(strong.coef_).max()),
                        "qrcp_max_abs_coefficient": float(np.abs(model.coef_).max()),
                        "swaps": strong.swaps_,
                        "selected": [names[i] for i in strong.selected_]}
    face = default_face()
    s["muscle_insertions"] = insertion_distances(face, corpus.nodes,
                                                 [names[i] for i in full_all.order_[:10]])
    s["paper"] = PAPER
    s["copied_pair"] = [COPY_SOURCE, COPY_TARGET]
    if video:
        u = corpus.utterances[n_train]
        d = u - u[0]
        pred = model.predict(d[:, model.selected_])
        dense_animation(out / "animation.mp4", face, corpus.nodes, pred,
                        progress=step("render"))
        s["figures"]["animation"] = "animation.mp4"
    _write_json(out / "summary.json", s)
    return s
