"""``facemech regions``: independent markers and eigenregions of the user's marker files
(Lucero & Munhall 2008), with the parsing of its utterance ranges and lengths."""

from __future__ import annotations

import contextlib
import json
import math
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..checks import check_value
from ..errors import InputError

__all__ = ["draw", "parse_length", "parse_ranges", "read_utterances", "regions", "report",
           "write"]


def parse_ranges(text: str | None, n: int, field: str) -> list[int] | None:
    """Utterance numbers such as ``"1-30"`` or ``"1,3,5-7"`` (1-based, inclusive) as 0-based
    indices below ``n``; None for None. ``field`` names the option in errors."""
    if text is None:
        return None
    out: list[int] = []
    try:
        for part in text.split(","):
            a, _, b = part.strip().partition("-")
            lo, hi = int(a), int(b or a)
            out.extend(range(lo - 1, hi))
    except ValueError:
        raise InputError("expected ranges such as 1-30 or 1,3,5-7", field=field) from None
    if any(i < 0 or i >= n for i in out):
        raise InputError(f"utterance numbers must lie in 1..{n}", field=field)
    return out


def parse_length(text: str | None, field: str) -> float | None:
    """A length such as ``"0.5mm"``, ``"0.05cm"`` or ``"0.0005"`` (metres) in metres, finite and in
    (0, 0.1] m; None for None or ``"auto"``. ``field`` names the option in errors."""
    if text is None or text == "auto":
        return None
    from ..units import LENGTH_TO_M

    t, value = text.strip().lower(), None
    for unit in sorted(LENGTH_TO_M, key=len, reverse=True):
        if t.endswith(unit):
            with contextlib.suppress(ValueError):
                value = float(t[: -len(unit)]) * LENGTH_TO_M[unit]
            break
    if value is None:
        try:
            value = float(t)
        except ValueError:
            raise InputError(f"not a length: {text!r} (e.g. 0.5mm)", field=field) from None
    if not (math.isfinite(value) and 0 < value <= 0.1):
        raise InputError(f"{text!r} is not a length between 0 and 100 mm", field=field)
    return value


def read_utterances(files: Sequence[str | Path], *, neutral: str | Path = "first",
                    units: str | None = None):
    """Marker files, one utterance each, with the same markers.

    Parameters
    ----------
    files : marker files (any format :func:`facemech.read_markers` reads)
    neutral : "first" (each utterance's first frame) or a marker file whose first frame is the
        neutral
    units : length unit of files that carry none

    Returns
    -------
    (utterances, names, neutral, rate) : (frames, markers, 3) arrays in metres, the marker
        names, "first" or a (markers, 3) array in metres, and the first file's rate (Hz)
    """
    from ..io.markers import read_markers

    sets = [read_markers(f, units=units) for f in files]
    names = sets[0].names
    sets = [sets[0]] + [_same_markers(ms, names, f) for f, ms in zip(files[1:], sets[1:],
                                                                     strict=True)]
    for f, ms in zip(files, sets, strict=True):
        _no_gap(ms, f, "the utterance")
    base: str | np.ndarray = "first"
    if str(neutral) != "first":
        ref = _same_markers(read_markers(Path(neutral), units=units), names, neutral,
                            what="the neutral file lacks a marker of the utterances",
                            extra_ok=True)
        _no_gap(ref, neutral, "the neutral (first frame)", frames=1)
        base = ref.positions[0]
    return [ms.positions for ms in sets], names, base, sets[0].rate


def _same_markers(ms, names, path, *, what: str = "markers differ from the first file's",
                  extra_ok: bool = False):
    """``ms`` with the markers ``names``, in that order, matched as
    :func:`facemech.markerset.shared_names` matches them (``ul`` is ``UL``); an InputError
    naming the first marker one side lacks (or, without ``extra_ok``, has in excess)."""
    from ..markerset import shared_names

    pairs = dict(shared_names(names, ms.names, source=str(path)))
    lost = [n for n in names if n not in pairs]
    extra = [] if extra_ok else [m for m in ms.names if m not in pairs.values()]
    if lost or extra:
        raise InputError(what, source=str(path), field=(lost + extra)[0])
    return ms.select([pairs[n] for n in names]).renamed(names)


def _no_gap(ms, path, what: str, frames: int | None = None) -> None:
    """Refuse a gap in a marker file of the region analysis, naming the file, the marker and
    the frame (the analysis needs every sample)."""
    valid = ms.valid[:frames]
    if valid.all():
        return
    k, m = (int(i[0]) for i in np.nonzero(~valid))
    lost = int((~valid[:, m]).sum())
    inside = valid[:k, m].any() and valid[k:, m].any()  # fill-gaps fills interior gaps only
    hint = ("fill it (facemech markers fill-gaps) or drop the file" if inside else
            "cut the recording to where the marker is present (facemech markers trim) or drop "
            "the file")
    raise InputError(f"{what} has a gap at frame {k + 1} (t = {ms.time[k]:.3f} s; {lost} of "
                     f"{len(valid)} samples missing): {hint}", source=str(path),
                     field=ms.names[m])


def regions(files: Sequence[str | Path], output: str | Path, *, k: int | None = None,
            eps: str | float | None = None, neutral: str | Path = "first",
            train: str | None = None, test: str | None = None, method: str = "qrcp",
            units: str | None = None):
    """Fit, draw and write the region analysis of marker files into the folder ``output``.

    Parameters
    ----------
    files : marker files, one utterance each (see :func:`read_utterances`)
    output : folder for ``summary.json`` and the PNG figures
    k : independent markers (default: min(epsilon-rank, 10))
    eps : data precision: metres, or a length such as "0.5mm" (default: the noise floor)
    neutral : "first" or a marker file whose first frame is the neutral
    train, test : utterances to fit and to hold out, e.g. "1-30" and "31-40" (1-based)
    method : "qrcp" or "strong"
    units : length unit of files that carry none

    Returns
    -------
    facemech.analysis.lucero2008.RegionAnalysis, with its figures
    """
    from ..analysis.lucero2008 import analyse
    from ..atomic import check_output

    if k is not None:
        check_value("k", k)  # the command line's interval (facemech.checks)
    check_output(output, [*files, None if str(neutral) == "first" else neutral], folder=True,
                 field="-o")
    utts, names, base, rate = read_utterances(files, neutral=neutral, units=units)
    res = analyse(utts, names, k=k, method=method, neutral=base, rate=rate,
                  eps=eps if isinstance(eps, float) else parse_length(eps, "eps"),
                  train=parse_ranges(train, len(utts), "train"),
                  test=parse_ranges(test, len(utts), "test"))
    with _folder(output) as tmp:  # nothing half-written: the figures land together
        res = draw(res, tmp)
        write(res, tmp / "summary.json")
    return res


@contextlib.contextmanager
def _folder(output: str | Path):
    """A temporary folder beside ``output`` to fill; on success its files move into
    ``output`` (created), on error or interruption it is removed whole."""
    import shutil
    import tempfile

    from ..atomic import pending_folder

    out = Path(output)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    try:
        with pending_folder(tmp):
            yield tmp
            if not out.exists():
                tmp.rename(out)
            else:
                for f in sorted(tmp.iterdir()):
                    f.replace(out / f.name)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


def report(res, output: str | Path) -> list[str]:
    """What ``facemech regions`` prints."""
    return [f"epsilon {res.eps_mm:.3f} mm, rank {res.rank} of {res.markers}; k = {res.k}",
            "independent markers: " + ", ".join(res.selected),
            *(f"note: {n}" for n in res.notes), f"summary and figures -> {output}/"]


def write(result, path: str | Path) -> Path:
    """Write a region analysis' (:class:`~facemech.analysis.lucero2008.RegionAnalysis`,
    :class:`~facemech.analysis.lucero2008.Lucero2008`) ``as_dict()`` as JSON
    (``summary.json``), atomically."""
    from ..atomic import atomic_path

    with atomic_path(path, suffix=".json") as tmp:
        tmp.write_text(json.dumps(result.as_dict(), indent=2))
    return Path(path)


def _plane(rest_mm: np.ndarray) -> tuple[np.ndarray, list[int], str | None]:
    """The markers' layout for the maps: (markers, 2) mm in the two axes where the rest
    positions spread most (x, y for a face; z, y for midsagittal articulography), those axes,
    and why no map can be drawn (None: one can), for fewer than 3 markers or all on one line."""
    spread = np.ptp(rest_mm, axis=0)
    axes = sorted(np.argsort(spread)[-2:].tolist(), key=lambda a: (a == 1, a))  # y last
    xy = rest_mm[:, axes]
    if len(xy) < 3:
        return xy, axes, f"{len(xy)} markers (a map interpolates between at least 3)"
    sv = np.linalg.svd(xy - xy.mean(axis=0), compute_uv=False)
    if sv[0] == 0 or sv[1] < 1e-6 * sv[0]:
        return xy, axes, ("the markers lie on one line at rest (a map needs them spread over a "
                          "plane)")
    return xy, axes, None


def draw(result, folder: str | Path):
    """Draw the analysis' PNG figures into ``folder`` (created): R values (Fig. 2), the first
    eigenregions and orthogonal regions, and with held-out utterances the errors against k and
    a predicted trajectory (Fig. 9), and the stability of the R values.

    The maps are drawn in the plane where the markers spread most at rest (x and y for a
    face, z and y for midsagittal articulography); with fewer than 3 markers, or all on one
    line, they are left out and ``notes`` says so.

    Returns the result with its ``figures`` (name -> file name) and ``notes``.
    """
    from ..viz import regions as fig

    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    figures = {"r_values": fig.r_values_figure(out / "r_values.png", result.r_values_mm,
                                               result.eps_mm, "R values (Fig. 2)").name}
    xy, axes, why = _plane(result.rest_mm)
    if why is None:
        figures.update(_maps(out, xy, result, f"{'xyz'[axes[0]]} (mm)"))
    notes = () if why is None else (f"no eigenregion or orthogonal-region maps: {why}",)
    if result.held_out_error is not None:
        rows = result.held_out_error
        figures["errors"] = fig.error_figure(
            out / "errors.png", [r_.k for r_ in rows], [r_.mean_abs_error_mm for r_ in rows],
            [r_.relative_error for r_ in rows], [r_.pca_mean_abs_error_mm for r_ in rows]).name
    t = result.trajectory
    if t is not None:
        figures["trajectory"] = fig.trajectory_figure(
            out / "trajectory.png", t.time_s, t.recorded_mm, t.predicted_mm,
            f"{t.marker}, held-out utterance {t.utterance}, k = {result.k} (Fig. 9)").name
    if result.stability is not None:
        figures["stability"] = fig.stability_figure(out / "stability.png",
                                                    list(result.stability.utterances),
                                                    result.stability.first_r_values_mm).name
    return replace(result, figures={k: str(v) for k, v in figures.items()}, notes=notes)


def _maps(out: Path, xy: np.ndarray, result, xlabel: str) -> dict:
    """The eigenregion and orthogonal-region maps (Figs. 4-7) at the layout ``xy`` (mm)."""
    from ..viz import regions as fig

    model, full, names = result.model, result.full, list(result.names)
    figures = {}
    maps, titles, marks = [], [], []
    for j in range(min(3, result.k)):
        vals = np.zeros(len(names))
        vals[model.secondary_] = model.coef_[j]
        vals[model.selected_[j]] = 1.0
        maps.append(vals)
        titles.append(f"eigenregion of {names[model.selected_[j]]}")
        marks.append(int(model.selected_[j]))
    if maps:
        figures["eigenregions"] = fig.region_maps(out / "eigenregions.png", xy, maps, titles,
                                                  marks, xlabel=xlabel).name
    r = full.R_
    omaps, otitles, omarks = [], [], []
    for j in range(min(3, r.shape[0])):
        vals = np.zeros(len(names))
        vals[full.order_] = r[j] / r[j, j]
        omaps.append(vals)
        otitles.append(f"orthogonal region {j + 1} ({names[full.order_[j]]})")
        omarks.append(int(full.order_[j]))
    figures["orthogonal_regions"] = fig.region_maps(out / "orthogonal_regions.png", xy, omaps,
                                                    otitles, omarks, xlabel=xlabel).name
    return figures
