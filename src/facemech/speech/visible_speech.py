"""Visible speech per phone: is each phone's lip shape visible when the face says a sentence?

Given a phone alignment (:class:`facemech.speech.alignment.Alignment`) and the simulated
epidermis of the face that said it, each phone is measured for what its class asks of the lips:
a bilabial's lip gap at its middle (:func:`facemech.speech.mouth.mouth_measures`); an open
vowel's largest lip gap within it, and whether it stands between two bilabials; a rounded
phone's (:data:`ROUNDED_LABELS`) largest forward displacement of both lip centres at once; a
labiodental's smallest distance from the upper incisors' edge (:func:`upper_incisor_edge`) to
the lower lip's top (:func:`lower_lip_top`), contact within :data:`CONTACT_MM`. The sentence:
the lower lip's peak speed (:func:`peak_lower_lip_speed`) and the lower incisor's
(:func:`incisor_speed`) against :data:`REAL_JAW_PEAK_MM_S`. Every phone keeps its eSpeak stress;
:func:`summarize` tabulates the phones against :data:`CRITERIA`. Pure: numbers in, numbers out
(m, s inside; the summary in mm and mm/s). Definitions in full: docs/visible-speech.md.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..geometry.teeth import teeth_depth
from .mouth import midline_lip_pair, mouth_measures, opening_width
from .phone_labels import phone_stress, reads_stress
from .phoneclass import phone_classes

__all__ = ["CLOSURE_MIN_S", "CONTACT_MM", "CRITERIA", "ROUND_ASPECT_MIN", "SEAL_MM",
           "closure_duration", "OPEN_EXTRA_LABELS", "ROUNDED_LABELS", "PhoneMeasure",
           "REAL_JAW_PEAK_MM_S", "class_table", "incisor_distance", "incisor_speed",
           "lower_lip_speed", "lower_lip_top",
           "measure_phones", "peak_lower_lip_speed", "summarize", "teeth_shown",
           "upper_incisor_edge"]

#: mm: the lower lip touches the upper incisors when it comes this close to their edge
CONTACT_MM = 1.0
#: mm: the lips are sealed where their midline gap is this or less (the bilabials' criterion)
SEAL_MM = 0.5
#: s: a bilabial's lips stay sealed at least this long (real bilabial closures last 70-120 ms
#: in read speech)
CLOSURE_MIN_S = 0.050
#: a rounded phone's opening, where the lips part, at least this high for its width
ROUND_ASPECT_MIN = 0.5
#: mm/s, the fastest lower incisor of the real recordings (EMA and X-ray microbeam, a
#: read sentence and repeated syllables: peak jaw speeds 58-186 mm/s); recorded beside the
#: lower lip's speed, not a criterion
REAL_JAW_PEAK_MM_S = 186.0
#: eSpeak labels of /ɔ/ (counted open; phoneclass's class ``open_rounded``)
OPEN_EXTRA_LABELS = frozenset({"O:", "O", "O2"})
#: eSpeak labels of /u ʊ w oʊ/
ROUNDED_LABELS = frozenset({"u:", "u", "U", "w", "w#", "W", "oU"})
#: the pass criteria (lengths mm, speeds mm/s, shares of the phones)
CRITERIA = {
    "bilabial": {"gap_max_mm": 0.5, "share": 0.95, "none_above_mm": 1.0},
    "open": {"aperture_min_mm": 8.0, "share": 0.90, "median_min_mm": 10.0},
    "rounded": {"forward_min_mm": 2.0, "share": 0.90},
    "labiodental": {"contact_mm": CONTACT_MM, "share": 0.90},
    "closure": {"min_ms": 1e3 * CLOSURE_MIN_S, "share": 0.90},
    "round_opening": {"aspect_min": ROUND_ASPECT_MIN, "share": 0.90},
    "speed": {"peak_min_mm_s": 100.0, "peak_max_mm_s": 250.0},
}


@dataclass(frozen=True)
class PhoneMeasure:
    """One phone's measures (m); a measure the phone's group does not use is None.

    Attributes
    ----------
    label, start, end : the eSpeak label (with its stress mark) and interval (s)
    classes : articulatory classes (:func:`facemech.speech.phoneclass.phone_classes`)
    stress : ``"primary"``, ``"secondary"`` or None (unstressed or not marked)
    group : the group: ``"bilabial"``, ``"open"``, ``"rounded"``, ``"labiodental"``
        or None
    between_bilabials : the phones on both sides are bilabials
    lip_gap_mid : m, the lip gap at the middle of the phone (every phone)
    lips_forward_mid : m, the forward displacement of both lip centres (the smaller) at the
        middle of the phone (every phone)
    aperture_max : m, the largest lip gap within the phone (open vowels)
    forward_max : m, the largest forward displacement of both lip centres within the phone
        (rounded phones); ``upper_forward`` and ``lower_forward`` at that frame
    incisor_distance : m, the smallest distance within the phone from the upper incisors'
        edge to the lower lip (labiodentals)
    closure : s, how long the lips stay sealed (midline gap <= :data:`SEAL_MM`) about the
        phone's most closed frame (bilabials; :func:`closure_duration`)
    opening_aspect : the opening's height over its width at the phone's middle (rounded
        phones whose lips part there; :func:`facemech.speech.mouth.opening_width`), else None
    width_ratio : the mouth's corner-to-corner width at the phone's middle over its rest
        width (rounded phones)
    upper_teeth, lower_teeth : m, how much of the upper and lower incisors shows between the
        lips at the phone's middle (:func:`teeth_shown`; None without the jaw's poses)
    lip_edge : m, the lower lip's visible edge (its midline contact twin) above the upper
        incisors' edge, as seen from the front, at the phone's middle (labiodentals;
        negative: below)
    """

    label: str
    start: float
    end: float
    classes: tuple[str, ...]
    stress: str | None
    group: str | None
    between_bilabials: bool
    lip_gap_mid: float
    lips_forward_mid: float
    aperture_max: float | None = None
    forward_max: float | None = None
    upper_forward: float | None = None
    lower_forward: float | None = None
    incisor_distance: float | None = None
    closure: float | None = None
    opening_aspect: float | None = None
    width_ratio: float | None = None
    upper_teeth: float | None = None
    lower_teeth: float | None = None
    lip_edge: float | None = None

    def to_dict(self) -> dict:
        """The row in mm (lengths rounded to 0.01 mm), times in s."""
        out = asdict(self)
        for k in ("lip_gap_mid", "lips_forward_mid", "aperture_max", "forward_max", "upper_forward",
                  "lower_forward", "incisor_distance", "upper_teeth", "lower_teeth", "lip_edge"):
            v = out.pop(k)
            out[f"{k}_mm"] = None if v is None else round(1e3 * v, 2)
        out["classes"] = list(self.classes)
        out["closure_ms"] = None if out["closure"] is None else round(1e3 * out["closure"], 1)
        del out["closure"]
        return out


def _base(label: str) -> str:
    return label.strip().lstrip("',%=")


def _group(label: str, classes: tuple[str, ...]) -> str | None:
    base = _base(label)
    if classes[:1] == ("bilabial",):
        return "bilabial"
    if classes[:1] == ("labiodental",):
        return "labiodental"
    if base in ROUNDED_LABELS:
        return "rounded"
    if classes[:1] in (("open",), ("open_rounded",)) or base in OPEN_EXTRA_LABELS:
        return "open"
    return None


def upper_incisor_edge(model) -> np.ndarray:
    """Position (3,) m of the upper central incisors' edge at the midline, as the renderer
    draws it (:mod:`facemech.viz.dentition`): ``UPPER_EDGE_BELOW_STOMION`` (3 mm) below the
    stomion, its labial face :func:`facemech.geometry.teeth.teeth_depth` behind the upper
    lip's centre. Fixed to the skull."""
    from ..viz.dentition import UPPER_EDGE_BELOW_STOMION

    rest = model.rest_positions
    lm = model.landmarks
    ul = rest[lm["upper_lip_center"]]
    st = rest[lm["stomion"]] if "stomion" in lm else 0.5 * (ul + rest[lm["lower_lip_center"]])
    return np.array([st[0], st[1] - UPPER_EDGE_BELOW_STOMION, ul[2] - teeth_depth(model)])


def lower_lip_top(model, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The lower lip's top at the midline: the cut face of the mouth slit under the lower lip.

    The slit is a cut through the lip (:mod:`facemech.speech.mouth`): at the midline it runs
    from the lower lip's epidermal contact twin (the visible edge of the vermilion) back
    through the tissue to its twin in the deep layer, which rests on the teeth. The results
    hold the epidermis only, so the back end is taken at the rest offset of the deep twin from
    the epidermal one, carried along with the epidermal twin (the lip's top translates; its
    compression is not seen).

    Parameters
    ----------
    model : FaceModel
    positions : (frames, nodes, 3) or (nodes, 3) m, at least the epidermis

    Returns
    -------
    front, back : (frames, 3) or (3,) m, the ends of the lip's top
    """
    p = np.asarray(positions, float)
    _, lo, _ = midline_lip_pair(model)
    rest = model.rest_positions
    front = p[..., lo, :]
    return front, front + (rest[lo + 2 * model.n_surface] - rest[lo])


def incisor_distance(model, positions: np.ndarray) -> np.ndarray:
    """Distance (m) from the upper incisors' edge (:func:`upper_incisor_edge`) to the lower
    lip's top (:func:`lower_lip_top`, a segment) per frame; 0 where the edge lies on it.

    ``positions`` : (frames, nodes, 3) or (nodes, 3) m; returns (frames,) or a float.
    """
    edge = upper_incisor_edge(model)
    a, b = lower_lip_top(model, positions)
    ab = b - a
    s = np.clip(np.sum((edge - a) * ab, axis=-1) / np.sum(ab * ab, axis=-1), 0.0, 1.0)
    d = np.linalg.norm(a + s[..., None] * ab - edge, axis=-1)
    return float(d) if np.ndim(d) == 0 else d


def teeth_shown(model, positions: np.ndarray, jaw_pose: np.ndarray) -> tuple[np.ndarray,
                                                                             np.ndarray]:
    """How much (m, vertically at the midline) of the upper and of the lower central incisors
    shows between the lips: the part of each crown's labial face below the upper lip's edge
    and above the lower lip's edge (the midline contact twins), the lower crown's also below
    the upper incisors' edge (the overbite hides it behind them); 0 where none shows.

    ``positions`` : (frames, nodes, 3) or (nodes, 3) m; ``jaw_pose`` : (frames, 3) or (3,)
    (angle rad, shift_y m, shift_z m). Returns (upper, lower), each (frames,) or a float.
    """
    from ..geometry.teeth import lower_incisor_point
    from ..solvers.jaw import move_points
    from ..viz.dentition import LOWER, UPPER

    p = np.asarray(positions, float)
    single = p.ndim == 2
    if single:
        p = p[None]
    poses = np.atleast_2d(np.asarray(jaw_pose, float))
    up, lo, _ = midline_lip_pair(model)
    top, bottom = p[:, up, 1], p[:, lo, 1]  # the lips' edges
    edge = upper_incisor_edge(model)[1]
    tip = lower_incisor_point(model)
    low = np.array([move_points(tip, q, model.hinge_point, model.hinge_axis)[0, 1]
                    for q in poses])
    upper = np.clip(np.minimum(top, edge + UPPER[0].height) - np.maximum(bottom, edge), 0, None)
    lower = np.clip(np.minimum(np.minimum(top, edge), low)
                    - np.maximum(bottom, low - LOWER[0].height), 0, None)
    if single:
        return float(upper[0]), float(lower[0])
    return upper, lower


def lower_lip_speed(time: np.ndarray, positions: np.ndarray, model) -> np.ndarray:
    """Speed (m/s) of the landmark ``lower_lip_center`` per frame: the norm of its velocity
    by central differences (:func:`numpy.gradient`) over ``time`` (s)."""
    k = model.landmarks["lower_lip_center"]
    p = np.asarray(positions, float)[:, k]
    v = np.gradient(p, np.asarray(time, float), axis=0)
    return np.linalg.norm(v, axis=1)


def peak_lower_lip_speed(time: np.ndarray, positions: np.ndarray, model) -> float:
    """The largest speed (m/s) of ``lower_lip_center`` over the whole utterance."""
    return float(lower_lip_speed(time, positions, model).max())


def incisor_speed(time: np.ndarray, jaw_pose: np.ndarray, model) -> np.ndarray:
    """Speed (m/s) per frame of the lower incisor tip
    (:func:`facemech.geometry.teeth.lower_incisor_point`) moved by the jaw's poses (frames, 3:
    angle rad, shift_y m, shift_z m; ``Simulation.jaw_pose``): the norm of its velocity by
    central differences over ``time`` (s)."""
    from ..geometry.teeth import lower_incisor_point
    from ..solvers.jaw import move_points

    tip = lower_incisor_point(model)
    poses = np.atleast_2d(np.asarray(jaw_pose, float))
    p = np.array([move_points(tip, q, model.hinge_point, model.hinge_axis)[0] for q in poses])
    if len(p) < 2:
        return np.zeros(len(p))
    return np.linalg.norm(np.gradient(p, np.asarray(time, float), axis=0), axis=1)


def closure_duration(time: np.ndarray, gap: np.ndarray, start: float, end: float,
                     seal: float = 1e-3 * SEAL_MM) -> float:
    """s, how long the lips stay sealed (``gap`` <= ``seal``, m) in the run of frames about the
    most closed frame within [start, end] (the nearest frame to the middle when none lies
    there); the run's ends are interpolated to where the gap crosses ``seal``. 0 when the
    lips do not seal there."""
    t = np.asarray(time, float)
    g = np.asarray(gap, float)
    idx = _window(t, start, end)
    k = int(idx[np.argmin(g[idx])])
    if g[k] > seal:
        return 0.0
    a = k
    while a > 0 and g[a - 1] <= seal:
        a -= 1
    b = k
    while b < len(g) - 1 and g[b + 1] <= seal:
        b += 1
    ta = t[a] if a == 0 else t[a - 1] + (t[a] - t[a - 1]) * (g[a - 1] - seal) / \
        (g[a - 1] - g[a])
    tb = t[b] if b == len(g) - 1 else t[b] + (t[b + 1] - t[b]) * (seal - g[b]) / \
        (g[b + 1] - g[b])
    return float(tb - ta)


def _window(time: np.ndarray, start: float, end: float) -> np.ndarray:
    """Frames within [start, end]; the nearest frame to the middle when none is."""
    idx = np.nonzero((time >= start) & (time <= end))[0]
    if idx.size == 0:
        idx = np.array([int(np.argmin(np.abs(time - 0.5 * (start + end))))])
    return idx


def measure_phones(alignment, model, time: np.ndarray, positions: np.ndarray, *,
                   voice: str | None = None, jaw_pose: np.ndarray | None = None
                   ) -> list[PhoneMeasure]:
    """Measure every phone of an alignment on a simulated face.

    Parameters
    ----------
    alignment : Alignment
        Phones with times (s) in eSpeak mnemonics (the stress marks kept), or IPA or ARPABET
        (then the groups that name eSpeak labels, :data:`ROUNDED_LABELS` and
        :data:`OPEN_EXTRA_LABELS`, are found by class only, and stress is read from IPA's
        ``ˈ ˌ`` or ARPABET's digits where the alignment marks any: :func:`reads_stress`).
    model : FaceModel
        The face that said it (``sim.model``).
    time : (frames,) s
        The frames' times, on the alignment's clock (``sim.time``).
    positions : (frames, nodes, 3) m
        Positions of at least the epidermis (``sim.positions``).
    voice : str, optional
        The eSpeak voice (default: ``alignment.meta["voice"]``): eSpeak's ``0`` is open in
        en-us only.
    jaw_pose : (frames, 3), optional
        The jaw's poses (``sim.jaw_pose``): with them, the teeth shown at each phone's middle
        (:func:`teeth_shown`).

    Returns
    -------
    list of PhoneMeasure
        One per phone with classes (eSpeak's bare ``;`` and pauses are left out).
    """
    time = np.asarray(time, float)
    p = np.asarray(positions, float)[:, : model.n_surface]
    voice = alignment.meta.get("voice") if voice is None else voice
    m = mouth_measures(model, p)
    gap = m["lip_gap"]
    lm, rest = model.landmarks, model.rest_positions
    rest_width = float(np.linalg.norm(rest[lm["mouth_corner_left"]]
                                      - rest[lm["mouth_corner_right"]]))
    incisor_dist = incisor_distance(model, p)
    shown = None if jaw_pose is None else teeth_shown(model, p, jaw_pose)
    lip_edge = lower_lip_top(model, p)[0][:, 1] - upper_incisor_edge(model)[1]
    phones = [(s, phone_classes(s.label, alignment.notation, source=alignment.source,
                                voice=voice)) for s in alignment.phones]
    marked = reads_stress(alignment)
    phones = [(s, c) for s, c in phones if c and c != ("pause",)]
    groups = [_group(s.label, c) for s, c in phones]
    out = []
    for k, ((seg, classes), group) in enumerate(zip(phones, groups, strict=True)):
        idx = _window(time, seg.start, seg.end)
        extra: dict = {}
        if group == "open":
            extra["aperture_max"] = float(gap[idx].max())
        elif group == "rounded":
            j = idx[int(np.argmax(m["lips_forward"][idx]))]
            extra.update(forward_max=float(m["lips_forward"][j]),
                         upper_forward=float(m["upper_forward"][j]),
                         lower_forward=float(m["lower_forward"][j]))
        elif group == "labiodental":
            extra["incisor_distance"] = float(incisor_dist[idx].min())
            extra["lip_edge"] = float(np.interp(seg.mid, time, lip_edge))
        if group == "bilabial":
            extra["closure"] = closure_duration(time, gap, seg.start, seg.end)
        elif group == "rounded":
            j = int(np.argmin(np.abs(time - seg.mid)))
            w = float(opening_width(model, p[j]))
            extra["width_ratio"] = 1.0 + float(m["width_change"][j]) / rest_width
            if gap[j] > 1e-3 * SEAL_MM and w > 0:
                extra["opening_aspect"] = float(gap[j]) / w
        if shown is not None:
            j = int(np.argmin(np.abs(time - seg.mid)))
            extra.update(upper_teeth=float(shown[0][j]), lower_teeth=float(shown[1][j]))
        between = _between_bilabials(phones, groups, k)
        out.append(PhoneMeasure(
            label=seg.label, start=float(seg.start), end=float(seg.end), classes=classes,
            stress=phone_stress(seg.label, alignment.notation) if marked else None,
            group=group, between_bilabials=bool(between),
            lip_gap_mid=float(np.interp(seg.mid, time, gap)),
            lips_forward_mid=float(np.interp(seg.mid, time, m["lips_forward"])), **extra))
    return out


def _between_bilabials(phones: list, groups: list, k: int) -> bool:
    """Whether phone ``k`` lies between two bilabials that touch it in time."""
    seg = phones[k][0]
    return (0 < k < len(phones) - 1 and groups[k - 1] == "bilabial"
            and groups[k + 1] == "bilabial"
            and phones[k - 1][0].end >= seg.start - 1e-9
            and phones[k + 1][0].start <= seg.end + 1e-9)


def _stats(values_mm: list[float], passed: list[bool]) -> dict:
    v = np.asarray(values_mm, float)
    return {"n": int(v.size),
            "share_passing": round(float(np.mean(passed)), 3) if v.size else None,
            "median_mm": round(float(np.median(v)), 2) if v.size else None,
            "min_mm": round(float(v.min()), 2) if v.size else None,
            "max_mm": round(float(v.max()), 2) if v.size else None}


def _closure_row(bil: list) -> dict:
    """The bilabials' closure durations (ms) against :data:`CRITERIA`'s ``closure``."""
    c = CRITERIA
    v = [1e3 * p.closure for p in bil if p.closure is not None]
    row = {"n": len(v)}
    ok = [x >= c["closure"]["min_ms"] for x in v]
    row.update({"share_passing": round(float(np.mean(ok)), 3) if v else None,
                "median_ms": round(float(np.median(v)), 1) if v else None,
                "shortest_ms": round(float(min(v)), 1) if v else None,
                "worst": _worst([p for p in bil if p.closure is not None], v, min)})
    if row["worst"] is not None:  # the value in ms
        row["worst"]["value_ms"] = row["worst"].pop("value_mm")
    row["met"] = bool(v) and row["share_passing"] >= c["closure"]["share"]
    return row


def _labiodental_front_row(lab: list) -> dict:
    """The labiodentals' lip edge at the upper incisors seen from the front (mm), the lower
    incisors hidden, against :data:`CRITERIA`'s ``labiodental``."""
    c = CRITERIA
    front = [p for p in lab if p.lip_edge is not None]
    v = [1e3 * abs(p.lip_edge) for p in front]
    ok = [x <= c["labiodental"]["contact_mm"] and (p.lower_teeth is None or
                                                    1e3 * p.lower_teeth <= SEAL_MM)
          for x, p in zip(v, front, strict=True)]
    row = _stats(v, ok)
    row["worst"] = _worst(front, v, max)
    row["lower_teeth_hidden"] = sum(1 for p in front if p.lower_teeth is not None
                                    and 1e3 * p.lower_teeth <= SEAL_MM)
    row["met"] = bool(front) and row["share_passing"] >= c["labiodental"]["share"]
    return row


def _round_opening_row(rnd: list) -> dict:
    """The rounded phones' opening (height over width where the lips part) against
    :data:`CRITERIA`'s ``round_opening``; sealed ones counted apart."""
    c = CRITERIA
    seen = [p for p in rnd if p.opening_aspect is not None]
    ratios = [p.width_ratio for p in rnd if p.width_ratio is not None]
    v = [p.opening_aspect for p in seen]
    ok = [x >= c["round_opening"]["aspect_min"] for x in v]
    return {
        "n": len(v), "sealed": len(rnd) - len(v),
        "share_passing": round(float(np.mean(ok)), 3) if v else None,
        "median_aspect": round(float(np.median(v)), 2) if v else None,
        "median_width_ratio": round(float(np.median(ratios)), 2) if ratios else None,
        "met": (not v and bool(rnd)) or (bool(v) and float(np.mean(ok))
                                            >= c["round_opening"]["share"])}


def summarize(phones: list[PhoneMeasure], peak_speeds: list[float] | None = None) -> dict:
    """The phones (and sentences) against the pass criteria (:data:`CRITERIA`).

    Parameters
    ----------
    phones : measures of any number of sentences (:func:`measure_phones`)
    peak_speeds : m/s, each sentence's peak lower-lip speed (:func:`peak_lower_lip_speed`)

    Returns
    -------
    dict
        Per group: ``n``, ``share_passing`` (of the phones meeting the group's per-phone
        threshold), ``median_mm``, ``min_mm``, ``max_mm``, ``worst`` (the worst phone's label
        and value, mm) and ``met`` (the criterion as a whole). ``open`` counts stressed
        phones only (primary or secondary) and adds ``between_bilabials`` (the same for those
        of them between two bilabials); ``rounded`` adds the medians of each lip. ``speed``:
        ``n``, ``min``, ``median``, ``max`` (mm/s), ``share_passing`` and ``met``.
    """
    c = CRITERIA
    out: dict = {}

    bil = [p for p in phones if p.group == "bilabial"]
    v = [1e3 * p.lip_gap_mid for p in bil]
    ok = [x <= c["bilabial"]["gap_max_mm"] for x in v]
    row = _stats(v, ok)
    row["worst"] = _worst(bil, v, max)
    row["met"] = bool(bil) and row["share_passing"] >= c["bilabial"]["share"] and \
        max(v) <= c["bilabial"]["none_above_mm"]
    out["bilabial"] = row

    def open_row(sel):
        v = [1e3 * p.aperture_max for p in sel]
        ok = [x >= c["open"]["aperture_min_mm"] for x in v]
        row = _stats(v, ok)
        row["worst"] = _worst(sel, v, min)
        row["met"] = bool(sel) and row["share_passing"] >= c["open"]["share"] and \
            row["median_mm"] >= c["open"]["median_min_mm"]
        return row

    opn = [p for p in phones if p.group == "open" and p.stress is not None]
    out["open"] = open_row(opn)
    out["open"]["between_bilabials"] = open_row([p for p in opn if p.between_bilabials])

    rnd = [p for p in phones if p.group == "rounded"]
    v = [1e3 * p.forward_max for p in rnd]
    row = _stats(v, [x >= c["rounded"]["forward_min_mm"] for x in v])
    row["worst"] = _worst(rnd, v, min)
    if rnd:
        row["median_upper_mm"] = round(float(np.median([1e3 * p.upper_forward for p in rnd])), 2)
        row["median_lower_mm"] = round(float(np.median([1e3 * p.lower_forward for p in rnd])), 2)
    row["met"] = bool(rnd) and row["share_passing"] >= c["rounded"]["share"]
    out["rounded"] = row

    lab = [p for p in phones if p.group == "labiodental"]
    v = [1e3 * p.incisor_distance for p in lab]
    row = _stats(v, [x <= c["labiodental"]["contact_mm"] for x in v])
    row["worst"] = _worst(lab, v, max)
    row["met"] = bool(lab) and row["share_passing"] >= c["labiodental"]["share"]
    out["labiodental"] = row

    out["closure"] = _closure_row(bil)
    out["labiodental_front"] = _labiodental_front_row(lab)
    out["round_opening"] = _round_opening_row(rnd)

    if peak_speeds is not None:
        s = np.asarray(peak_speeds, float) * 1e3
        lo, hi = c["speed"]["peak_min_mm_s"], c["speed"]["peak_max_mm_s"]
        ok = (s >= lo) & (s <= hi)
        out["speed"] = {"n": int(s.size),
                        "min_mm_s": round(float(s.min()), 1) if s.size else None,
                        "median_mm_s": round(float(np.median(s)), 1) if s.size else None,
                        "max_mm_s": round(float(s.max()), 1) if s.size else None,
                        "share_passing": round(float(ok.mean()), 3) if s.size else None,
                        "met": bool(s.size) and bool(ok.all())}
    return out


def class_table(phones: list[PhoneMeasure]) -> dict:
    """Per articulatory class (a phone's first class): ``n``, and the median, smallest and
    largest lip gap and forward displacement of both lips at the phones' middles (mm)."""
    out: dict = {}
    for cls in dict.fromkeys(p.classes[0] for p in phones):
        sel = [p for p in phones if p.classes[0] == cls]
        row: dict = {"n": len(sel)}
        for name, key in (("gap", "lip_gap_mid"), ("forward", "lips_forward_mid")):
            v = 1e3 * np.array([getattr(p, key) for p in sel])
            row.update({f"{name}_median_mm": round(float(np.median(v)), 2),
                        f"{name}_min_mm": round(float(v.min()), 2),
                        f"{name}_max_mm": round(float(v.max()), 2)})
        out[cls] = row
    return out


def _worst(sel: list[PhoneMeasure], values: list[float], pick) -> dict | None:
    if not sel:
        return None
    k = int(np.argmax(values) if pick is max else np.argmin(values))
    return {"label": sel[k].label, "start_s": round(sel[k].start, 3),
            "value_mm": round(values[k], 2)}
