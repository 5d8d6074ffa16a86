"""One path from a recording to results: a subject folder made once from a face and a rest
recording, then any number of recordings analysed against it.

``make_subject`` writes ``SUBJECT/``:

- ``face.npz``: the face (a built-in face warped to the rest markers, or the given face file);
- ``mapping.csv``: each marker's epidermal node (``marker,node``);
- ``rest.csv``: the rest markers in the model's frame, as a landmark CSV (``name,x,y,z``, mm);
- ``subject.json``: the lab -> model similarity, the head markers' model positions, the jaw
  markers, the fit's residuals;
- ``subject.png``: the face and its markers, front and side, to check by eye.

``analyse`` takes a recording through head-motion correction, the subject's frame, gap filling
and resampling, inverts it on the subject's face and writes the results, the comparison
statistics, the figures and (optionally) the movie into ``OUT/``.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..atomic import atomic_path, check_output
from ..errors import InputError
from .inputs import LOWPASS_HZ, Analysis, Preparation
from .outcome import Written

__all__ = ["Analysis", "Preparation", "Subject", "analyse", "make_subject", "read_subject",
           "usable_head"]

SURFACES = (".obj", ".ply", ".stl")
#: Hz, the low-pass of the head markers before the rigid fits: head motion is slower than
#: speech, and a fit's rotation error grows with the distance from the head markers
HEAD_LOWPASS_HZ = 4.0
#: s, the longest gap of a head marker filled before the rigid fits (the head moves slowly)
HEAD_GAP_S = 1.0
#: m, a marker farther than this from the skin after the fit is not on the face (a reference
#: or body marker) and is left out with a note; nearer than this but over 10 mm is an error
OFF_FACE = 0.050


@dataclass(frozen=True)
class Subject:
    """A subject folder, read back.

    Attributes
    ----------
    folder : the folder
    lab_to_model : :class:`~facemech.kinematics.alignment.Similarity` of the rest recording
    mapping : marker -> epidermal node of ``face.npz``
    head : head-marker names -> (3,) model-frame rest positions, m (empty: no head markers)
    chin_marker, jaw_second_marker : the jaw markers (None: the jaw is estimated)
    info : everything ``subject.json`` holds
    """

    folder: Path
    lab_to_model: object
    mapping: dict
    head: dict
    chin_marker: str | None
    jaw_second_marker: str | None
    info: dict

    @property
    def face(self) -> Path:
        return self.folder / "face.npz"


def _names(text, field: str) -> tuple[str, ...]:
    if text is None:
        return ()
    out = tuple(n.strip() for n in (text.split(",") if isinstance(text, str) else text)
                if n.strip())
    if len(set(out)) != len(out):
        raise InputError(f"a marker is named twice in {text!r}", field=field)
    return out


def usable_head(ms, head: tuple[str, ...], *, source: str) -> tuple[tuple[str, ...], list]:
    """The head markers of ``head`` that ``ms`` holds with data (at least 3), and notes on
    those left out."""
    have = tuple(h for h in head if h in ms.names and np.isfinite(ms.marker(h)).any())
    if len(have) < 3:
        gone = [h for h in head if h not in have]
        raise InputError(f"fewer than 3 head markers have data ({', '.join(gone)} missing): a "
                         "rigid fit needs three", source=source, field=gone[0] if gone else
                         "head")
    left_out = [h for h in head if h not in have]
    return have, ([f"head markers without data, left out: {', '.join(left_out)}"]
                  if left_out else [])


def _fill_head(ms, head: tuple[str, ...]):
    """Gaps of the head markers filled (up to :data:`HEAD_GAP_S`) and low-passed at
    :data:`HEAD_LOWPASS_HZ`: the head moves slowly, and a frame with fewer than three of them
    loses every marker in the rigid fit."""
    from ..kinematics.gaps import fill_gaps
    from ..kinematics.resample import lowpass

    part, _, _ = fill_gaps(ms.select(list(head)), int(round(HEAD_GAP_S * ms.rate)))
    if HEAD_LOWPASS_HZ < 0.5 * ms.rate:
        part = lowpass(part, HEAD_LOWPASS_HZ)
    pos = ms.positions.copy()
    pos[:, [ms.index(h) for h in head]] = part.positions
    return ms.with_positions(pos)


def rest_positions(ms, head: tuple[str, ...], interval: tuple[float, float], *,
                   source: str) -> tuple[np.ndarray, tuple, dict]:
    """Each marker's mean position (markers, 3), m, over the rest ``interval`` (s) of a
    recording, after head-motion correction with the ``head`` markers (:func:`usable_head`).
    Markers without data in the interval are left out. Returns (positions, names, notes)."""
    from ..kinematics.rigid import head_correct

    notes: dict = {"notes": []}
    if head:
        hc = head_correct(_fill_head(ms, head), head)
        ms, notes["head_residual_mm"] = hc.markers, hc.summary()["residual_mm"]
    inside = (ms.time >= interval[0] - 1e-9) & (ms.time <= interval[1] + 1e-9)
    if inside.sum() < 1:
        raise InputError(f"no frame in the rest interval {interval[0]:g}-{interval[1]:g} s",
                         source=source, field="rest")
    seen = np.isfinite(ms.positions[inside]).all(axis=2)
    counts = seen.sum(axis=0)
    rest = np.einsum("fm,fmk->mk", seen, np.where(seen[..., None], ms.positions[inside], 0.0))
    rest = rest / np.maximum(counts, 1)[:, None]
    missing = [n for n, c in zip(ms.names, counts, strict=True) if c == 0]
    if missing:
        notes["notes"].append(
            f"markers without data in the rest interval, left out: {', '.join(missing)}")
    keep = [k for k, c in enumerate(counts) if c > 0]
    return rest[keep], tuple(ms.names[k] for k in keep), notes


def _align(rest: np.ndarray, names: tuple[str, ...], model, frame: tuple[str, ...],
           skip: tuple[str, ...], source: str):
    """Lab -> model similarity: by the markers named as the face's sites, else by the
    anatomical frame and the skin. Returns (similarity, how)."""
    from ..kinematics.alignment import fit_to_skin, similarity_fit
    from ..kinematics.frames import basis_from_points
    from ..solvers.forward import marker_nodes

    site_names, site_nodes = marker_nodes(model)
    sites = dict(zip(site_names, site_nodes, strict=True))
    named = [n for n in names if n in sites and n not in skip]
    if len(named) >= 4:
        idx = [names.index(n) for n in named]
        fit = similarity_fit(rest[idx], model.rest_positions[[sites[n] for n in named]])
        return fit, f"by name ({len(named)} markers named as the face's sites)"
    if len(frame) != 3:
        raise InputError("name three markers for the anatomical frame (RIGHT,LEFT,FRONT), or "
                         "name at least 4 markers as the face's landmarks", source=source,
                         field="frame")
    for n in frame:
        if n not in names:
            raise InputError("frame marker without data at rest", source=source, field=n)
    basis = basis_from_points(*(rest[names.index(n)] for n in frame))
    on_skin = [k for k, n in enumerate(names) if n not in skip]
    centre = np.median(rest[on_skin], axis=0)  # a reference or body marker far off: not used
    on_skin = [k for k in on_skin if np.linalg.norm(rest[k] - centre) <= 0.15]
    fit = fit_to_skin(rest[on_skin], model.rest_positions[: model.n_surface], basis,
                      source=source)
    return fit, f"by the skin (anatomical frame {','.join(frame)}, closest points)"


def _map(moved: np.ndarray, names: tuple[str, ...], model, skip: tuple[str, ...], source: str,
         *, limit: float = 0.010) -> tuple[dict, dict, list]:
    """marker -> closest epidermal node (or its named site). A marker more than
    :data:`OFF_FACE` from the skin is not on the face and is left out (returned in the third
    item); one farther than ``limit`` (m) but nearer is an error, as are two markers on one
    node."""
    from scipy.spatial import cKDTree

    from ..solvers.forward import marker_nodes

    sites = dict(zip(*marker_nodes(model), strict=True))
    skin = model.rest_positions[: model.n_surface]
    d, idx = cKDTree(skin).query(moved)
    mapping, dist, off = {}, {}, []
    for k, n in enumerate(names):
        if n in skip:
            continue
        node = int(sites[n]) if n in sites else int(idx[k])
        gap = float(np.linalg.norm(moved[k] - skin[node]))
        if gap > OFF_FACE and n not in sites:
            off.append(f"{n} ({gap * 1e3:.0f} mm)")
            continue
        if gap > limit:
            raise InputError(f"{gap * 1e3:.1f} mm from the skin after alignment (limit "
                             f"{limit * 1e3:.0f} mm): a head marker (--head), or the wrong unit "
                             "or frame?", source=source, field=n)
        twin = next((m for m, v in mapping.items() if v == node), None)
        if twin is not None:
            raise InputError(f"on the same node as {twin}: markers closer than the mesh "
                             "spacing", source=source, field=n)
        mapping[n], dist[n] = node, gap
    return mapping, dist, off


def make_subject(face: str | Path, markers: str | Path, output: str | Path, *,
                 head: str | None = None, frame: str | None = None,
                 landmarks: str | Path | None = None, units: str | None = None,
                 rest: str | tuple[float, float] | None = None, chin_marker: str | None = None,
                 jaw_second_marker: str | None = None, warp: bool | None = None,
                 progress=None) -> Written:
    """Make a subject folder from a face and a rest recording.

    Parameters
    ----------
    face : a built-in face (``default``...), a face file (.npz) or a scan (OBJ/PLY/STL, with
        ``landmarks``)
    markers : a recording (C3D, TRC, CSV) whose ``rest`` interval (s) is the face at rest
    output : the subject folder
    head : comma-separated head markers (at least 3; on a headband or the skull, not the skin)
    frame : ``RIGHT,LEFT,FRONT`` markers of an anatomical frame (see
        :mod:`facemech.kinematics.frames`); not needed when at least 4 markers are named as the
        face's landmarks or markers
    landmarks, units : the scan's landmark CSV; length unit of files that carry none
    rest : ``"START,STOP"`` seconds of rest in ``markers``, inside the recording (None: its
        first :data:`DEFAULT_REST_S` s, or all of a shorter one)
    chin_marker, jaw_second_marker : jaw markers for :func:`analyse` (None: estimated)
    warp : warp the face so that its nodes sit on the rest markers (default: for built-in faces)
    progress : staged callback; stages ``subject`` (0..4 of 4)

    Returns
    -------
    Written : ``data`` the :class:`Subject`
    """
    from ..geometry.builder import load_face
    from ..io.markers import read_markers
    from ..kinematics.mapping import warp_face
    from ..markerset import MarkerSet
    from .emg import as_interval

    face_path, out, src = Path(str(face)), Path(output), str(markers)
    check_output(out, [markers, landmarks, face_path if face_path.exists() else None],
                 folder=True, field="-o")
    say = progress or (lambda *a: None)
    head_names, frame_names = _names(head, "head"), _names(frame, "frame")
    interval = as_interval(rest, "rest")
    ms = read_markers(markers, units=units)
    for n in (chin_marker, jaw_second_marker, *frame_names):
        if n is not None and n not in ms.names:
            raise InputError("marker not in the recording", source=src, field=n)
    if interval is None:
        t0 = float(ms.time[0])
        interval = (t0, min(t0 + DEFAULT_REST_S, float(ms.time[-1])))
    else:
        check_interval(ms, interval, source=src, field="rest")
    ms, unlabelled = labelled(ms, (chin_marker, jaw_second_marker, *frame_names, *head_names))
    say("subject", 0, 4)
    if face_path.suffix.lower() in SURFACES:
        if landmarks is None:
            raise InputError("a scan needs its landmarks (--landmarks)", source=str(face),
                             field="landmarks")
        import tempfile

        from ..atomic import pending_folder
        from .faces import build_face_file

        with tempfile.TemporaryDirectory() as tmp, pending_folder(tmp):  # gone if interrupted
            model = build_face_file(face_path, landmarks, Path(tmp) / "f.npz", units="auto").data
        warp = bool(warp)
    else:
        model = load_face(face)
        warp = (not face_path.exists()) if warp is None else warp
    head_names, head_notes = usable_head(ms, head_names, source=src) if head_names else ((), [])
    rest_m, names, notes = rest_positions(ms, head_names, interval, source=src)
    notes["notes"] = unlabelled + head_notes + notes["notes"]
    say("subject", 1, 4)
    fit, how = _align(rest_m, names, model, frame_names, head_names, src)
    moved = fit(rest_m)
    mapping, dist, off = _map(moved, names, model, head_names, src)
    if off:
        notes["notes"].append(f"markers not on the face, left out: {', '.join(off)}")
    say("subject", 2, 4)
    on_skin = [n for n in names if n in mapping]
    rest_set = MarkerSet(moved[None, [names.index(n) for n in on_skin]], tuple(on_skin), 60.0)
    if warp:
        model = warp_face(model, rest_set, mapping)
    say("subject", 3, 4)
    model.save(out / "face.npz")
    with atomic_path(out / "mapping.csv") as tmp:
        tmp.write_text("marker,node\n" + "".join(f"{n},{v}\n" for n, v in mapping.items()))
    with atomic_path(out / "rest.csv") as tmp:  # a landmark CSV (name,x,y,z; mm)
        tmp.write_text("name,x,y,z\n" + "".join(
            f"{n},{p[0] * 1e3:.4f},{p[1] * 1e3:.4f},{p[2] * 1e3:.4f}\n"
            for n, p in zip(on_skin, rest_set.positions[0], strict=True)))
    info = {"face": str(face), "warped": bool(warp), "recording": src,
            "rest_s": list(interval), "alignment": how, "lab_to_model": fit.as_dict(),
            "marker_to_skin_mm": {n: round(v * 1e3, 3) for n, v in dist.items()},
            "head": {h: moved[names.index(h)].tolist() for h in head_names},
            "chin_marker": chin_marker, "jaw_second_marker": jaw_second_marker, **notes}
    with atomic_path(out / "subject.json") as tmp:
        tmp.write_text(json.dumps(info, indent=2))
    from ..viz.subject import subject_figure

    subject_figure(out / "subject.png", model, moved, names, mapping, head_names)
    say("subject", 4, 4)
    subj = read_subject(out)
    worst = max(dist.values())
    line = (f"subject of {len(mapping)} markers on {model.name} ({how}; scale {fit.scale:.3f}, "
            f"markers {np.median(list(dist.values())) * 1e3:.2f} mm from the skin, at most "
            f"{worst * 1e3:.2f} mm; warped: {bool(warp)}) -> {out}/")
    return Written(out, subj, "\n".join([*(f"  {n}" for n in notes["notes"]), line]))


#: s, the rest interval of a recording when none is given: its first half second
DEFAULT_REST_S = 0.5

#: names of unlabelled trajectories: Vicon Nexus's ``*12``, Qualisys's ``Unlabeled 12`` (and
#: the British spelling), Cortex's ``unnamed12``
UNLABELLED = re.compile(r"^(\*\d+|unlabell?ed[ _-]*\d*|unnamed[ _-]*\d*)$", re.IGNORECASE)


def labelled(ms, named=()) -> tuple[object, list[str]]:
    """``ms`` without its unlabelled trajectories (:data:`UNLABELLED`), unless ``named``
    names them, and a note listing those left out (empty when none)."""
    drop = [n for n in ms.names if UNLABELLED.match(n) and n not in named]
    if not drop:
        return ms, []
    keep = [n for n in ms.names if n not in drop]
    if not keep:
        raise InputError(f"every trajectory is unlabelled ({', '.join(drop[:5])}...): label "
                         "the markers first", source=ms.meta.get("source"), field=drop[0])
    return ms.select(keep), [f"unlabelled trajectories left out: {', '.join(drop)} (name one "
                             "with --head, --frame or --chin-marker to use it)"]


def check_interval(ms, interval: tuple[float, float], *, source: str, field: str) -> None:
    """Refuse an interval (s) that reaches outside the recording's time span (half a frame of
    tolerance at each end)."""
    half = 0.5 / ms.rate
    t0, t1 = float(ms.time[0]), float(ms.time[-1])
    a, b = interval
    if a < t0 - half or b > t1 + half:
        raise InputError(f"--{field} {a:g},{b:g} s reaches outside the recording ({t0:g} to "
                         f"{t1:g} s)", source=source, field=field)


def read_subject(folder: str | Path) -> Subject:
    """Read a subject folder written by :func:`make_subject`."""
    from ..kinematics.alignment import Similarity

    folder = Path(folder)
    path = folder / "subject.json"
    if not path.is_file():
        raise InputError("not a subject folder (no subject.json): make it with "
                         "`facemech subject`", source=str(folder))
    try:
        info = json.loads(path.read_text())
        mapping = {}
        for line in (folder / "mapping.csv").read_text().splitlines()[1:]:
            name, node = line.split(",")
            mapping[name] = int(node)
        fit = Similarity.from_dict(info["lab_to_model"])
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        raise InputError(f"unreadable subject folder ({exc})", source=str(folder)) from None
    if not (folder / "face.npz").is_file():
        raise InputError("the subject folder has no face (face.npz): make it again with "
                         "`facemech subject`", source=str(folder), field="face.npz")
    return Subject(folder, fit, mapping, {k: np.array(v) for k, v in info["head"].items()},
                   info.get("chin_marker"), info.get("jaw_second_marker"), info)


def prepare(subj: Subject, ms, *, max_gap: float, rate: float, source: str,
            lowpass_hz: float | None = LOWPASS_HZ):
    """A recording in the subject's model frame: lab -> model, gaps up to ``max_gap`` s filled,
    low-passed at ``lowpass_hz`` (None: not), head motion removed against the subject's head
    markers, resampled to ``rate`` Hz, only the mapped markers. Returns (MarkerSet, notes)."""
    from ..kinematics.gaps import fill_gaps
    from ..kinematics.resample import lowpass, resample
    from ..kinematics.rigid import head_correct, rigid_fit

    missing = [n for n in subj.mapping if n not in ms.names]
    if len(missing) == len(subj.mapping):
        raise InputError("none of the subject's markers is in the recording", source=source,
                         field="markers")
    ms = ms.with_positions(subj.lab_to_model(ms.positions))
    notes = [f"markers absent from the recording: {', '.join(missing)}"] if missing else []
    ms, filled, left = fill_gaps(ms, int(round(max_gap * ms.rate)))
    if filled or left:
        notes.append(f"gaps: {len(filled)} filled (<= {max_gap:g} s), {len(left)} left")
    if lowpass_hz and lowpass_hz < 0.5 * ms.rate:
        ms = lowpass(ms, lowpass_hz)
        notes.append(f"low-passed at {lowpass_hz:g} Hz (4th-order Butterworth, zero phase)")
    elif lowpass_hz:
        notes.append(f"not low-passed: {lowpass_hz:g} Hz is not below the recording's Nyquist "
                     f"frequency ({0.5 * ms.rate:g} Hz)")
    if subj.head:
        head, left_out = usable_head(ms, tuple(subj.head), source=source)
        notes += left_out
        hc = head_correct(_fill_head(ms, head), head)
        cols = [ms.index(h) for h in head]
        head_now = np.nanmean(hc.markers.positions[:, cols], axis=0)
        r, t = rigid_fit(head_now, np.array([subj.head[h] for h in head]))
        ms = hc.markers.with_positions(hc.markers.positions @ r.T + t)
        res = hc.summary()
        notes.append(f"head motion removed with {', '.join(head)}: residual median "
                     f"{res['residual_mm']['median']:.2f} mm, max "
                     f"{res['residual_mm']['max']:.2f} mm")
        if res["unfixed_frames"]:
            notes.append(f"{len(res['unfixed_frames'])} frames without three head markers "
                         "have no markers")
    ms = ms.select([n for n in ms.names if n in subj.mapping])
    empty = [n for n in ms.names if not np.isfinite(ms.marker(n)).any()]
    if empty:
        notes.append(f"markers without data, left out: {', '.join(empty)}")
        ms = ms.select([n for n in ms.names if n not in empty])
    if abs(ms.rate - rate) > 1e-6 * rate:
        notes.append(f"resampled from {ms.rate:g} Hz to {rate:g} Hz")
        ms = resample(ms, rate)
    return ms, notes


#: the lsq inversion's options in :func:`analyse` (:meth:`Analysis.fit_options`): longer and
#: stronger than the method's own defaults (2, 0.3): a recording is noisy (a twin with 0.1 mm
#: of marker noise recovers every determined muscle with r >= 0.88 with them, RIS and DAO at
#: 0.73 and 0.75 without; docs/recordings.md)
ANALYSE_LSQ = Analysis().fit_options()


def analyse(subject: str | Path, recording: str | Path, output: str | Path, *,
            analysis: Analysis | None = None, preparation: Preparation = Preparation(),
            preset: str = "anatomical", options: dict | None = None, progress=None,
            **keywords) -> Written:
    """Analyse a recording against a subject folder into the folder ``output``.

    Writes ``markers.csv`` (the prepared markers: model frame, mm, the model's rate) and its
    ``mapping.csv`` (the subject's nodes of the markers recorded),
    ``result.nc`` (the inversion and its re-animated face), ``controls.png`` (the inverted
    controls, +-2 SE), ``comparison.json`` (:func:`facemech.workflows.compare.compare_files` of
    the re-animation against the markers), ``summary.json`` and, with ``video``,
    ``movie.mp4``.

    Parameters
    ----------
    subject : a folder made by :func:`make_subject`
    recording : C3D, TRC or CSV of the same markers, in the lab, any rate
    output : the results folder
    analysis : the method, controls, noise, lsq window and smoothness, and the movie
        (:class:`Analysis`); its fields may also be given as keywords (``method=``,
        ``controls=``, ``noise=``, ``video=``, ...)
    preparation : the recording's unit, gaps filled and low-pass (:class:`Preparation`)
    preset : as :func:`facemech.workflows.invert.invert`
    options : the method's options (None: ``analysis``'s, :data:`ANALYSE_LSQ` by default)
    progress : staged callback: ``prepare``, ``invert (lsq)``, ``render``

    Returns
    -------
    Written : ``data`` a dict of the stages' numbers (as ``summary.json``)
    """
    from ..io.markers import read_markers, write_markers
    from ..jaw.inputs import JawMarkers
    from . import compare, invert

    analysis = replace(analysis or Analysis(), **keywords)
    out, src = Path(output), str(recording)
    check_output(out, [recording], folder=True, field="-o")
    subj = read_subject(subject)
    say = progress or (lambda *a: None)
    say("prepare", 0, 1)
    params = invert.parameters(preset)
    ms, notes = prepare(subj, read_markers(recording, units=preparation.units),
                        max_gap=preparation.max_gap, rate=params.params.frame_rate, source=src,
                        lowpass_hz=preparation.lowpass)
    invert.check_marker_set(ms, src)  # what would stop the inversion: before anything is written
    write_markers(out / "markers.csv", ms, units="mm")
    with atomic_path(out / "mapping.csv") as tmp:  # the subject's, for the markers recorded
        tmp.write_text("marker,node\n" + "".join(f"{n},{subj.mapping[n]}\n" for n in ms.names))
    jaw = [n if n in ms.names and np.isfinite(ms.marker(n)).all() else None
           for n in (subj.chin_marker, subj.jaw_second_marker)]
    if subj.chin_marker is not None and None in jaw[: 2 if subj.jaw_second_marker else 1]:
        notes.append(f"the jaw markers are missing or have gaps longer than "
                     f"{preparation.max_gap:g} s in "
                     "the recording: the jaw is estimated")
        jaw = [None, None]
    say("prepare", 1, 1)
    if options is None:
        options = analysis.fit_options()
    res = invert.invert(invert.MarkerFile(out / "markers.csv", "mm", out / "mapping.csv"),
                        out / "result.nc", face=subj.face, params=params,
                        jaw=JawMarkers(chin_marker=jaw[0], jaw_second_marker=jaw[1]),
                        inversion=analysis.inversion(),
                        options=options, figure=out / "controls.png", progress=progress)
    cmp = compare.compare_files(out / "result.nc", out / "markers.csv")
    with atomic_path(out / "comparison.json") as tmp:
        tmp.write_text("\n".join(compare.report(cmp, as_json=True)))
    if analysis.video:
        from .pictures import render_movie

        render_movie(out / "result.nc", (out / "movie.mp4",), progress=progress)
    err = res.error_summary()
    summary = {"subject": str(subject), "recording": src, "frames": len(res.time),
               "markers": list(ms.names), "notes": notes + list(res.notes),
               "error_mm": {"median": err["median_mm"], "max": err["max_mm"]},
               "determined": [n for n, ok in zip(res.control_names, res.identifiable,
                                                 strict=True) if ok]}
    with atomic_path(out / "summary.json") as tmp:
        tmp.write_text(json.dumps(summary, indent=2))
    line = (f"{summary['frames']} frames of {len(ms.names)} markers analysed: per-frame error "
            f"median {err['median_mm']:.3f} mm, max {err['max_mm']:.3f} mm; determined: "
            f"{', '.join(summary['determined'])} -> {out}/")
    return Written(out, summary, "\n".join([*(f"  {n}" for n in summary["notes"]), line]))
