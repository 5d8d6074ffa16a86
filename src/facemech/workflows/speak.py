"""Text, or a recording with its alignment, to a talking face: the ``speak`` workflow.

1. The audio and its phone alignment: eSpeak NG (:func:`facemech.speech.tts.synthesize`, with
   :data:`LEAD_IN_S` of silence before and :data:`TAIL_S` after), or a recorded WAV with a
   Praat TextGrid (:func:`facemech.speech.alignment_io.read_textgrid`).
2. Muscle activity and jaw angle per 60-Hz frame, blended by dominance
   (:func:`facemech.speech.coarticulation.controls_from_alignment`) and by default planned for
   the face's dynamics (:func:`facemech.speech.planning.plan_controls`; ``plan=False``: the blend).
3. The forward simulation (:func:`facemech.simulate`; when planned, the kept iteration's), the
   tongue tip's pose (:func:`facemech.speech.tongue.tongue_tip`) joining the results.
4. Blinks, gaze shifts and head motion (:mod:`facemech.speech.alive`, on by default).
5. The alignment as a TextGrid and a CSV with IPA labels (:func:`relabel_folder`: others).
6. The movie with the audio, and a manifest: settings, input hashes, stimulus parameters
   (:func:`facemech.analysis.describe.describe`) and the liveliness's times and laws.

Every file is written atomically; the folder's manifest names them all.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..checks import check_value
from ..errors import InputError
from .inputs import Alive, Recording, Speaking

__all__ = ["FILES", "LEAD_IN_S", "TAIL_S", "Alive", "Recording", "Speaking", "Spoken",
           "relabel_folder", "speak", "text_items", "write_alignment"]

#: s of silence put before and after synthesised speech, so that the face starts at rest and
#: has the time to anticipate the first phone (muscle activity leads the sound by 100 ms and
#: the lips take longer to get there) and to come back to rest after the last
LEAD_IN_S = 0.3
TAIL_S = 0.2

#: the files ``speak`` writes into its folder
FILES = {"audio": "speech.wav", "textgrid": "alignment.TextGrid", "alignment": "alignment.csv",
         "controls": "controls.csv", "results": "result.nc", "movie": "movie.mp4",
         "manifest": "manifest.json"}


@dataclass(frozen=True)
class Spoken:
    """What :func:`speak` made: the folder's files (name -> path), the alignment, the
    simulation, the stimulus parameters, the manifest (a dict, as written) and the results
    dataset."""

    files: dict
    alignment: object
    simulation: object
    description: dict
    manifest: dict = field(default_factory=dict)
    dataset: object = None  # the results as an xarray.Dataset (what result.nc holds)
    alive: object = None  # the blinks, gaze and head series (facemech.speech.alive.Alive)


def speak(
    out_dir: str | Path,
    text: str | None = None,
    *,
    recording: Recording | None = None,
    speaking: Speaking | None = None,
    face: str | Path = "default",
    preset: str = "anatomical",
    video=None,
    alive=None,
    progress: Callable[[str, int, int], None] | None = None,
    **keywords,
) -> Spoken:
    """Make the face say ``text`` (eSpeak NG), or speak in sync with a ``recording`` (a WAV
    and the TextGrid that aligns its phones); write everything into ``out_dir``.

    Parameters
    ----------
    out_dir : the folder (created; files in it are replaced, nothing else is touched)
    text : what to say; or give a ``recording`` instead
    recording : :class:`Recording` (audio, textgrid, tier names)
    speaking : :class:`Speaking`: voice, words per minute, articulation (``strength``,
        ``scale``), planning (``plan``, ``plan_iterations``; the manifest's ``plan`` records
        what was done), the phones' labels and ``video``; its fields may also be given as
        keywords (``voice=``, ``rate_wpm=``, ``strength=``, ``plan=`` True, False or a number
        of iterations, ...)
    face : a face file or a built-in face name
    preset : the physical preset (default ``anatomical``)
    video : the MP4 (H.264, the audio muxed in as AAC): a
        :class:`facemech.viz.video.RenderOptions`, True, False, or None (``speaking.video``,
        frontal+profile, 720p)
    alive : :class:`Alive` or :class:`facemech.speech.alive.Liveliness` (None: blinks, gaze
        and head motion on, the seed derived from the item's audio): shown in the movie,
        recorded in the manifest (``alive``); the simulation and the stimulus parameters stay
        in the head's frame
    progress : callable(stage, done, total)

    Returns
    -------
    Spoken
    """
    from ..analysis.describe import describe
    from ..io.activity import write_activity
    from ..io.results import file_hash, to_dataset, with_tongue, write_dataset
    from ..params import MUSCLE_GROUPS, preset_pair
    from ..physics.model import model as face_model
    from ..solvers.forward import simulate
    from ..speech.alignment_io import read_textgrid
    from ..speech.alive import Liveliness, liveliness
    from ..speech.coarticulation import controls_from_alignment
    from ..speech.phone_labels import LABEL_NOTATIONS, relabel
    from ..speech.tongue import tongue_tip
    from ..speech.wav import read_wav, write_wav

    speaking = Speaking.from_keywords(speaking, **keywords)
    render = speaking.video if video is None else video is not False
    look = None if video is None or isinstance(video, bool) else video
    alive = alive.liveliness() if isinstance(alive, Alive) else alive
    video, out = render and (look or True), Path(out_dir)

    audio, textgrid = (None, None) if recording is None else \
        (recording.audio, recording.textgrid)
    tiers = (None, None) if recording is None else (recording.word_tier, recording.phone_tier)
    alive = Liveliness() if alive is None else alive
    if not isinstance(alive, Liveliness):
        raise InputError("alive must be a facemech.speech.alive.Liveliness", field="alive")
    if (text is None) == (audio is None):
        raise InputError("give either text or --audio with --textgrid", field="text")
    if audio is not None and textgrid is None:
        raise InputError("--audio needs the recording's alignment (--textgrid)",
                         field="textgrid")
    if text is not None and not text.strip():
        raise InputError("nothing to say: the text is empty", field="text")
    labels = speaking.phone_labels
    if labels not in LABEL_NOTATIONS:
        raise InputError(f"unknown phone labels {labels!r} (expected "
                         f"{', '.join(LABEL_NOTATIONS)})", field="phone_labels")
    articulation = speaking.articulation()
    check_value("strength", articulation.strength)  # the command line's interval (checks.py)
    iterations = _plan_iterations(speaking.iterations())
    if out.exists() and not out.is_dir():
        raise InputError("output must be a folder", source=str(out), field="output")
    for given in (audio, textgrid):
        if given is not None and Path(given).resolve().parent == out.resolve() and \
                Path(given).name in FILES.values():
            raise InputError("an input would be overwritten by an output of the same name",
                             source=str(given), field="output")
    params, steps = preset_pair(preset)
    files = {k: out / v for k, v in FILES.items()}
    inputs: dict = {}
    if text is not None:
        from ..speech.tts import synthesize

        report(progress, "synthesise", 0, 1)
        speech = synthesize(text, voice=speaking.voice, rate_wpm=speaking.rate_wpm)
        samples, rate, alignment = _padded(speech.audio, speech.sample_rate, speech.alignment,
                                           LEAD_IN_S, TAIL_S)
        inputs["text"] = text
    else:
        try:
            samples, rate = read_wav(audio)
        except InputError as exc:
            raise InputError(exc.message, source=str(audio), field="audio") from None
        alignment = read_textgrid(textgrid, word_tier=tiers[0], phone_tier=tiers[1])
        dur = len(samples) / rate
        if alignment.phones and alignment.phones[-1].end > dur + 0.05:
            raise InputError(f"the alignment runs to {alignment.phones[-1].end:.2f} s, the "
                             f"audio lasts {dur:.2f} s: not this recording's TextGrid",
                             source=str(textgrid), field="time")
        if labels == "espeak" and alignment.notation != "espeak":  # before anything is written
            raise InputError("the recording's phones cannot be written as eSpeak NG codes "
                             "(only synthesised speech has them)", source=str(textgrid),
                             field="phone_labels")
        inputs["audio"] = file_hash(audio)
        inputs["textgrid"] = file_hash(textgrid)
    written = relabel(alignment, "ipa")  # before anything is written: a label without IPA
    model = face_model(face, params, steps=steps)  # after the inputs are checked: it takes a while
    out.mkdir(parents=True, exist_ok=True)
    write_wav(files["audio"], samples, rate)
    record = write_alignment(files, alignment, written)
    if iterations is None:
        t, act, jaw = controls_from_alignment(alignment, frame_rate=params.frame_rate,
                                              strength=articulation)
        sim = simulate(model, act, jaw,
                       progress=None if progress is None else
                       (lambda d, n: progress("simulate", d, n)))
        planned = {"planned": False}
    else:
        from ..speech.planning import plan_controls

        report(progress, "plan", 0, iterations + 1)
        made = plan_controls(alignment, model, strength=articulation,
                             iterations=iterations,
                             progress=None if progress is None else
                             (lambda d, n: progress("plan", d, n)))
        t, act, jaw, sim, planned = made.time, made.activity, made.jaw, made.simulation, \
            made.record
    write_activity(files["controls"], t, np.column_stack([act, jaw]),
                   (*MUSCLE_GROUPS, "jaw_angle"))
    ds = with_tongue(to_dataset(sim, inputs),
                     tongue_tip(alignment, sim.time, strength=articulation))
    write_dataset(files["results"], ds)
    desc = describe(ds).to_dict()
    lively = liveliness(ds["time"].values, samples, rate, alive)
    if video:
        from ..viz.video import FrameMotion, render_results

        options = None if video is True else video
        render_results(ds, files["movie"], options=options, audio=files["audio"],
                       progress=None if progress is None else
                       (lambda d, n: progress("render", d, n)),
                       motion=FrameMotion(lively.blink, lively.gaze, lively.head))
    else:
        files.pop("movie")
    manifest = {
        "kind": "facemech speak",
        "text": text,
        "voice": speaking.voice if text is not None else None,
        "rate_wpm": speaking.rate_wpm if text is not None else None,
        "face": str(face), "preset": params.name,
        "strength": articulation.strength, "scale": [str(r) for r in articulation.rules],
        "plan": planned,
        "inputs": inputs,
        "alignment": record,
        "frames": int(len(t)), "frame_rate_hz": float(params.frame_rate),
        "audio_sample_rate_hz": int(rate),
        "files": {k: p.name for k, p in files.items()},
        "stimulus": desc,
        "alive": lively.record(),
    }
    from ..atomic import atomic_path

    with atomic_path(files["manifest"]) as tmp:
        tmp.write_text(json.dumps(manifest, indent=2, default=_json_default))
    made = Spoken(files=files, alignment=alignment, simulation=sim, description=desc,
                  manifest=manifest, dataset=ds, alive=lively)
    return made if labels == "ipa" else relabel_folder(made, labels)


def write_alignment(files: dict, alignment, written) -> dict:
    """Write ``written`` (``alignment`` relabelled) as the folder's TextGrid and CSV, eSpeak
    NG's codes in a tier of their own when they were relabelled; return the manifest's
    ``alignment`` record (the notation, words, phone labels, eSpeak's codes, the source)."""
    from ..speech.alignment_io import ESPEAK_TIER, write_alignment_csv, write_textgrid

    kept = {ESPEAK_TIER: alignment.phones} if written is not alignment and \
        alignment.notation == "espeak" else {}
    write_textgrid(files["textgrid"], written, tiers=kept)
    write_alignment_csv(files["alignment"], written, tiers=kept)
    return {"notation": written.notation, "duration_s": alignment.duration,
            "words": [w.label for w in alignment.words], "phones": len(written.phones),
            "phone_labels": [p.label for p in written.phones],
            **({ESPEAK_TIER: [p.label for p in alignment.phones]} if kept else {}),
            "source": alignment.source,
            **{k: v for k, v in alignment.meta.items() if isinstance(v, (str, int, float))}}


def relabel_folder(spoken: Spoken, phone_labels: str) -> Spoken:
    """A :func:`speak` folder with its phones in ``phone_labels`` (``"ipa"``, as written,
    ``"arpabet"`` or ``"espeak"``: :func:`facemech.speech.phone_labels.relabel`): its TextGrid,
    CSV and manifest rewritten, each atomically. Returns the :class:`Spoken` with the new
    manifest (its ``alignment`` stays the one the face spoke)."""
    from dataclasses import replace

    from ..atomic import atomic_path
    from ..speech.phone_labels import relabel

    written = relabel(spoken.alignment, phone_labels)
    record = write_alignment(spoken.files, spoken.alignment, written)
    manifest = {**spoken.manifest, "alignment": record}
    with atomic_path(spoken.files["manifest"]) as tmp:
        tmp.write_text(json.dumps(manifest, indent=2, default=_json_default))
    return replace(spoken, manifest=manifest)


def _plan_iterations(plan) -> int | None:
    """``speak``'s ``plan`` as the planner's iterations (None: not planned); InputError naming
    the field ``plan`` or ``plan_iterations``."""
    from ..speech.planning import PLAN_ITERATIONS, check_iterations

    if plan is True:
        return PLAN_ITERATIONS
    if plan is False or plan is None:
        return None
    if isinstance(plan, (int, float, np.integer, np.floating)):
        return check_iterations(plan)
    raise InputError(f"plan must be True, False or a number of iterations, got {plan!r}",
                     field="plan")


def _padded(samples, rate: int, alignment, before: float, after: float):
    """Audio with ``before`` and ``after`` s of silence, and its alignment shifted to match."""
    from dataclasses import replace

    from ..speech.alignment import Segment

    k0, k1 = int(round(before * rate)), int(round(after * rate))
    audio = np.concatenate([np.zeros(k0, np.float32), np.asarray(samples, np.float32),
                            np.zeros(k1, np.float32)])
    dt = k0 / rate

    def shift(segs):
        return tuple(Segment(s.label, s.start + dt, s.end + dt) for s in segs)

    return audio, rate, replace(alignment, words=shift(alignment.words),
                                phones=shift(alignment.phones),
                                duration=len(audio) / rate)


def report(progress, stage: str, done: int, total: int) -> None:
    if progress is not None:
        progress(stage, done, total)


def _json_default(v):
    if isinstance(v, (np.floating, np.integer)):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    return str(v)


#: the columns a design table's text row may carry (besides the manipulations)
TEXT_ROW_COLUMNS = ("text", "face", "voice", "rate_wpm", "strength", "scale", "preset", "plan")
#: a text row's ``plan`` cell: yes or no (as the design's other switches), or a whole number of
#: the planner's iterations (0 to 20)
PLAN_CELLS = {"yes": True, "true": True, "on": True, "no": False, "false": False, "off": False}


def _plan_cell(value) -> bool | int:
    """A design row's ``plan`` cell as :func:`speak`'s ``plan`` (InputError naming ``plan``)."""
    from ..speech.planning import MAX_ITERATIONS

    text = str(value).strip().lower()
    if text in PLAN_CELLS:
        return PLAN_CELLS[text]
    try:
        number = float(text)
    except ValueError:
        number = float("nan")
    if not (number.is_integer() and 0 <= number <= MAX_ITERATIONS):
        raise InputError(f"{value!r} is not yes, no or a whole number of iterations from 0 to "
                         f"{MAX_ITERATIONS}", field="plan")
    return int(number)


def text_items(work_dir: str | Path, *, preset: str = "anatomical"):
    """The ``make_item`` hook of :func:`facemech.workflows.stimuli.run_design` for text rows: each
    row's text spoken by :func:`speak` (no movie) into ``work_dir/<key>/``.

    A row may set ``text``, ``face``, ``voice``, ``rate_wpm``, ``strength``, ``scale`` (rules
    ``KIND:KEY=FACTOR`` separated by ``;``, :mod:`facemech.speech.articulation`), ``preset``
    and ``plan`` (yes, the default, or no, or a number of the planner's iterations:
    :func:`speak`'s ``plan``).
    """
    from .._version import __version__

    work = Path(work_dir)

    def check(row: dict) -> tuple[int, Articulation]:
        """The row's columns and numbers, checked before any row runs: (rate_wpm, the
        strength with the row's scale rules)."""
        unknown = [k for k in row if k not in TEXT_ROW_COLUMNS]
        if unknown:
            raise InputError(f"unknown column {unknown[0]!r} (a text row has "
                             f"{', '.join(TEXT_ROW_COLUMNS)})", field=unknown[0])
        values = []
        for column, default, kind in (("rate_wpm", 160, int), ("strength", 1.0, float)):
            text = row.get(column, default)
            try:
                v = float(text)
            except (TypeError, ValueError):
                raise InputError(f"{text!r} is not a number", field=column) from None
            if not (np.isfinite(v) and v > 0):
                raise InputError(f"{text!r} must be a positive number", field=column)
            values.append(kind(v))
        _plan_cell(row.get("plan") or "yes")
        check_variant(str(row.get("voice", "en-us")))
        return values[0], Articulation.parse(row.get("scale") or None, strength=values[1])

    from ..speech.articulation import Articulation
    from ..speech.tts import check_variant

    def make_item(row: dict):
        from ..speech.alive import Liveliness

        rate, strength = check(row)
        key = _row_key(row, preset)
        # the item without blinks, gaze or head motion: the design draws them (its columns
        # blinks, gaze, head_motion, seed) on the finished stimulus's frames
        spoken = speak(work / key, str(row["text"]), voice=str(row.get("voice", "en-us")),
                       rate_wpm=rate, face=row.get("face", "default"),
                       preset=str(row.get("preset", preset)), strength=strength, video=False,
                       alive=Liveliness.off(), plan=_plan_cell(row.get("plan") or "yes"))
        return spoken.dataset, spoken.files["audio"]

    # the hook's version enters each item's key: items spoken before the planner became speak's
    # default (same package version) are made again, not reused
    make_item.version = f"speak {__version__}, controls planned by default"
    make_item.check = check
    return make_item


def _row_key(row: dict, preset: str) -> str:
    import hashlib

    text = json.dumps({**{k: str(v) for k, v in row.items()}, "preset_default": preset},
                      sort_keys=True)
    return "item-" + hashlib.sha256(text.encode()).hexdigest()[:12]
