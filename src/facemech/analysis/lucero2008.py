"""Region analysis runs: on user files (``facemech regions``) and on the embedded corpus
(``facemech experiment lucero2008``), with the seed's figures and numbers beside ours.

Computing here, drawing and writing in the commands' workflows: :func:`analyse` and
:func:`run_lucero2008` return frozen dataclasses (:class:`RegionAnalysis`,
:class:`Lucero2008`) whose ``as_dict()`` is the ``summary.json`` the commands write
(:func:`facemech.workflows.regions.write`); :func:`facemech.workflows.regions.draw` and
:func:`facemech.workflows.experiments.draw_lucero2008` make the figures (and the MP4) and
return the result with its ``figures`` recorded.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..params import Parameters
from .regions import IndependentMarkers

__all__ = ["HeldOutError", "InsertionDistances", "Lucero2008", "RegionAnalysis", "Stability",
           "TrajectoryError", "analyse", "insertion_distances", "run_lucero2008"]

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


@dataclass(frozen=True)
class HeldOutError:
    """Held-out error of the secondary markers with k independent markers (mm), and PCA's."""

    k: int
    mean_abs_error_mm: float
    relative_error: float
    pca_mean_abs_error_mm: float

    def as_dict(self) -> dict:
        return {"k": self.k, "mean_abs_error_mm": self.mean_abs_error_mm,
                "relative_error": self.relative_error,
                "pca_mean_abs_error_mm": self.pca_mean_abs_error_mm}


@dataclass(frozen=True)
class TrajectoryError:
    """A secondary marker's trajectory in the first held-out utterance, predicted from the k
    independent markers (Fig. 9).

    Attributes
    ----------
    marker : its name; ``utterance`` the utterance's number (1-based)
    max_error_xyz_mm : (3,) largest error per axis, mm
    time_s : (frames,) s
    recorded_mm, predicted_mm : (frames, 3) positions, mm
    """

    marker: str
    utterance: int
    max_error_xyz_mm: tuple
    time_s: np.ndarray
    recorded_mm: np.ndarray
    predicted_mm: np.ndarray

    def as_dict(self) -> dict:
        return {"marker": self.marker, "utterance": self.utterance,
                "max_error_xyz_mm": list(self.max_error_xyz_mm)}


@dataclass(frozen=True)
class Stability:
    """The first 12 R values (mm) fitted on the first 5, 10, ... training utterances."""

    utterances: tuple
    first_r_values_mm: np.ndarray  # (len(utterances), 12)

    def as_dict(self) -> dict:
        return {"utterances": list(self.utterances),
                "first_r_values_mm": self.first_r_values_mm.tolist()}


@dataclass(frozen=True)
class RegionAnalysis:
    """Independent markers and eigenregions of a set of utterances (:func:`analyse`).

    Attributes
    ----------
    utterances, markers : how many utterances and markers
    train, test : the fitted and held-out utterances (1-based)
    eps_mm, rank : the data precision (mm) and the epsilon-rank it gives
    k, method, k_exceeds_rank : independent markers of the model, its method, k > rank
    order : all markers in pivot order; ``r_values_mm`` their R values (mm)
    selected : the k independent markers
    residual_mm : ||R22||_F of the k-marker fit, mm
    max_abs_coefficient, max_abs_coefficient_qrcp : max |X| of the model and of plain QRCP
    strong_rrqr_swaps : column swaps of strong RRQR (0 for QRCP)
    held_out_error : per k, the held-out errors (None without held-out utterances)
    trajectory : a secondary marker's held-out trajectory (None without held-out utterances)
    stability : R values against training utterances (None: fewer than 10 or not asked)
    model : the fitted :class:`IndependentMarkers` with k markers
    full : the fitted :class:`IndependentMarkers` at the epsilon-rank (R values, regions)
    names : the markers in the data's order
    rest_mm : (markers, 3) the neutral positions, mm (the figures' layout)
    figures : figure name -> file name, filled by :func:`draw`
    notes : what the figures leave out and why, filled by :func:`draw`
    """

    utterances: int
    train: tuple
    test: tuple
    markers: int
    eps_mm: float
    rank: int
    k: int
    method: str
    k_exceeds_rank: bool
    order: tuple
    r_values_mm: np.ndarray
    selected: tuple
    residual_mm: float
    max_abs_coefficient: float
    max_abs_coefficient_qrcp: float
    strong_rrqr_swaps: int
    held_out_error: tuple | None
    trajectory: TrajectoryError | None
    stability: Stability | None
    model: IndependentMarkers
    full: IndependentMarkers
    names: tuple
    rest_mm: np.ndarray
    figures: dict = field(default_factory=dict)
    notes: tuple = ()

    def as_dict(self) -> dict:
        """The summary as ``summary.json`` holds it (numbers in mm)."""
        out = {"utterances": self.utterances, "train": list(self.train),
               "test": list(self.test), "markers": self.markers, "eps_mm": self.eps_mm,
               "rank": self.rank, "k": self.k, "method": self.method,
               "k_exceeds_rank": self.k_exceeds_rank, "order": list(self.order),
               "r_values_mm": self.r_values_mm.tolist(), "selected": list(self.selected),
               "residual_R22_F_mm": self.residual_mm,
               "max_abs_coefficient": self.max_abs_coefficient,
               "max_abs_coefficient_qrcp": self.max_abs_coefficient_qrcp,
               "strong_rrqr_swaps": self.strong_rrqr_swaps}
        if self.held_out_error is not None:
            out["held_out_error"] = [r.as_dict() for r in self.held_out_error]
        if self.trajectory is not None:
            out["trajectory"] = self.trajectory.as_dict()
        if self.stability is not None:
            out["stability"] = self.stability.as_dict()
        out["figures"] = dict(self.figures)
        if self.notes:
            out["notes"] = list(self.notes)
        return out


def _held_out(full, te, names, k_values) -> tuple:
    """The held-out errors (mm) for each k of ``k_values`` (default 1 .. min(markers - 1,
    20)); one factorisation serves every k."""
    ks = list(k_values) if k_values is not None else list(range(1, min(len(names) - 1,
                                                                         20) + 1))
    rows = []
    for kv in ks:
        e = full.with_k(kv).errors(te)
        rows.append(HeldOutError(kv, e["mean_abs_error"] * 1e3, e["relative_error"],
                                 e["pca_mean_abs_error"] * 1e3))
    return tuple(rows)


def _trajectory(model, te, names, first_test: int, neutral, rate, trajectory_marker):
    """The first held-out utterance's trajectory of a secondary marker (the first of
    ``trajectory_marker`` found, else the first secondary), predicted from the selected ones."""
    secondary = [names[i] for i in model.secondary_]
    wanted = [trajectory_marker] if isinstance(trajectory_marker, str) else list(
        trajectory_marker or [])
    name = next((w for w in wanted if w in secondary), secondary[0])
    j = names.index(name)
    u = np.asarray(te[0])
    base = u[0] if isinstance(neutral, str) else neutral
    pred = model.predict((u - base)[:, model.selected_])[:, j] + base[j]
    return TrajectoryError(
        name, first_test + 1, tuple((np.abs(pred - u[:, j]).max(axis=0) * 1e3).tolist()),
        np.arange(len(u)) / rate, u[:, j] * 1e3, pred * 1e3)


def analyse(utterances: Sequence[np.ndarray], names: Sequence[str], *,
            k: int | None = None, eps: float | None = None, method: str = "qrcp",
            train: Sequence[int] | None = None, test: Sequence[int] | None = None,
            neutral: str | np.ndarray = "first", rate: float = Parameters.frame_rate,
            k_values: Sequence[int] | None = None,
            trajectory_marker: str | Sequence[str] | None = None,
            stability: bool = True) -> RegionAnalysis:
    """Fit and evaluate the region analysis (Lucero & Munhall 2008).

    Parameters
    ----------
    utterances : (frames, markers, 3) arrays, metres, one per utterance
    names : the markers' names
    k : independent markers (default: min(epsilon-rank, 10))
    eps : data precision, m (default: the estimated noise floor)
    method : "qrcp" or "strong" (strong rank-revealing QR)
    train, test : 0-based utterances to fit and to hold out (default: fit all, hold out none)
    neutral : "first" (each utterance's first frame) or a (markers, 3) array, m
    rate : frame rate, Hz
    k_values : the k of the held-out errors (default 1 .. min(markers - 1, 20))
    trajectory_marker : the secondary marker(s) whose held-out trajectory to predict, first
        found (default: the first secondary marker)
    stability : also fit on the first 5, 10, ... training utterances (10 or more)

    Returns
    -------
    RegionAnalysis (numbers in mm; ``figures`` empty until :func:`draw`)
    """
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
    held, trajectory, stab = None, None, None
    if te:
        held = _held_out(full, te, names, k_values)
        trajectory = _trajectory(model, te, names, test[0], neutral, rate, trajectory_marker)
    if stability and len(tr) >= 10:
        counts = list(range(5, len(tr) + 1, 5))
        first = [IndependentMarkers(eps=full.eps_, neutral=neutral).fit(tr[:c]).r_values_[:12]
                 * 1e3 for c in counts]
        stab = Stability(tuple(counts), np.array(first))
    rest = np.asarray(tr[0][0] if isinstance(neutral, str) else neutral) * 1e3
    return RegionAnalysis(
        utterances=n_utt, train=tuple(i + 1 for i in train), test=tuple(i + 1 for i in test),
        markers=len(names), eps_mm=full.eps_ * 1e3, rank=full.rank_, k=kk, method=method,
        k_exceeds_rank=bool(kk > full.rank_), order=tuple(names[i] for i in full.order_),
        r_values_mm=full.r_values_ * 1e3, selected=tuple(names[i] for i in model.selected_),
        residual_mm=model.residual_ * 1e3,
        max_abs_coefficient=float(np.abs(model.coef_).max()) if model.coef_.size else 0.0,
        max_abs_coefficient_qrcp=float(np.abs(qrcp.coef_).max()) if qrcp.coef_.size else 0.0,
        strong_rrqr_swaps=int(getattr(model, "swaps_", 0)), held_out_error=held,
        trajectory=trajectory, stability=stab, model=model, full=full, names=tuple(names),
        rest_mm=rest)


@dataclass(frozen=True)
class InsertionDistances:
    """How far markers lie from the nearest muscle insertion, against random picks (mm)."""

    selected_mean_mm: float
    selected_mm: tuple
    random_mean_mm: float
    random_p_value: float

    def as_dict(self) -> dict:
        return {"selected_mean_mm": self.selected_mean_mm, "selected_mm": list(self.selected_mm),
                "random_mean_mm": self.random_mean_mm, "random_p_value": self.random_p_value}


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
    return InsertionDistances(float(d[sel].mean()), tuple(d[sel].tolist()), float(rand.mean()),
                              float(np.mean(rand <= d[sel].mean())))


@dataclass(frozen=True)
class Lucero2008:
    """The seed's analysis on the embedded corpus (:func:`run_lucero2008`).

    Attributes
    ----------
    analysis : the region analysis of the training utterances, the rest held out
    all_utterances : the epsilon-rank fit of every utterance: ``rank``, ``last_selected``,
        ``r_last_mm``, ``r_before_last_mm`` and ``noise_floor_mm``
    strong_rrqr : strong RRQR with k markers: ``bound``, ``max_abs_coefficient``,
        ``qrcp_max_abs_coefficient``, ``swaps``, ``selected``
    muscle_insertions : distances of the first 10 markers in pivot order to the insertions
    paper : what the paper reports (:data:`PAPER`)
    copied_pair : the eyelid markers of the seed's copied-displacement artifact
    corpus : the embedded corpus (:class:`~facemech.analysis.corpus.Corpus`)
    n_train : training utterances (the first ones)
    """

    analysis: RegionAnalysis
    all_utterances: dict
    strong_rrqr: dict
    muscle_insertions: InsertionDistances
    paper: dict
    copied_pair: tuple
    corpus: object
    n_train: int

    @property
    def figures(self) -> dict:
        return self.analysis.figures

    def as_dict(self) -> dict:
        """The summary as ``summary.json`` holds it (numbers in mm)."""
        return {**self.analysis.as_dict(), "all_utterances": self.all_utterances,
                "strong_rrqr": self.strong_rrqr,
                "muscle_insertions": self.muscle_insertions.as_dict(), "paper": self.paper,
                "copied_pair": list(self.copied_pair)}


def run_lucero2008(*, n_utterances: int = 40, frames: int = 60, k: int = 10,
                   progress: Callable[[str, int, int], None] | None = None) -> Lucero2008:
    """The seed's analysis on the embedded corpus of ``n_utterances`` (at least 8) of
    ``frames`` each; the first 75 % are fitted, the rest held out. ``progress`` is
    callable(stage, done, total)."""
    from ..geometry.builder import default_face
    from .corpus import COPY_SOURCE, COPY_TARGET, embedded_corpus
    from .regions import noise_floor

    if n_utterances < 8:
        raise InputError("needs at least 8 utterances", field="utterances")
    corpus = embedded_corpus(n_utterances, frames, progress=None if progress is None else
                             (lambda d, n: progress("simulate corpus", d, n)))
    n_train = max(2, round(0.75 * n_utterances))
    analysis = analyse(corpus.utterances, corpus.names, k=k, train=range(n_train),
                       test=range(n_train, n_utterances), rate=corpus.rate,
                       trajectory_marker=("jaw_low_L", "jaw_low_R", "jaw_L1", "jaw_R1",
                                          "chin_L"))
    model = analysis.model
    full_all = IndependentMarkers().fit(corpus.utterances)
    names = list(corpus.names)
    r = full_all.r_values_ * 1e3
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        strong = IndependentMarkers(k=k, method="strong", bound=2.0).fit(
            corpus.utterances[:n_train])
    return Lucero2008(
        analysis=analysis,
        all_utterances={"rank": full_all.rank_, "last_selected": names[full_all.order_[-1]],
                        "r_last_mm": float(r[-1]), "r_before_last_mm": float(r[-2]),
                        "noise_floor_mm": noise_floor(corpus.utterances) * 1e3},
        strong_rrqr={"bound": 2.0, "max_abs_coefficient": float(np.abs(strong.coef_).max()),
                     "qrcp_max_abs_coefficient": float(np.abs(model.coef_).max()),
                     "swaps": strong.swaps_, "selected": [names[i] for i in strong.selected_]},
        muscle_insertions=insertion_distances(default_face(), corpus.nodes,
                                              [names[i] for i in full_all.order_[:10]]),
        paper=PAPER, copied_pair=(COPY_SOURCE, COPY_TARGET), corpus=corpus, n_train=n_train)
