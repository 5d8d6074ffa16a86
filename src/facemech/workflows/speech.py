"""``facemech speak``, ``describe`` and ``stimuli``: a talking face from text or a recording,
the stimulus parameters of a result, and the stimuli of a design table."""

from __future__ import annotations

import json
from pathlib import Path

from .pictures import render_options

__all__ = ["describe_file", "describe_report", "describe_text", "speak",
           "speak_report", "stimuli", "stimuli_report"]


def speak(output: str | Path, text: str | None = None, *, video: bool = True, render=None,
          recording: dict | None = None, alive=None, scale=None, articulation=None,
          **options):
    """Make the face say ``text``, or speak in sync with a recorded voice, into the folder
    ``output``: :func:`facemech.workflows.speak.speak` (its keywords: ``voice``, ``rate_wpm``,
    ``face``, ``preset``, ``strength``, ``plan``, ``plan_iterations``, ``progress``), the MP4
    with ``video``, drawn with
    ``render`` (a :class:`facemech.viz.video.RenderOptions`, :func:`.pictures.render_options`;
    None: frontal+profile, 1280x720).

    The recorded voice: ``recording`` (a dict of ``audio``, ``textgrid``, ``word_tier``,
    ``phone_tier``), or the keywords ``audio``, ``textgrid`` and ``tiers`` (word, phone).
    ``alive``: a :class:`facemech.speech.alive.Liveliness`, or a dict of ``blinks``, ``gaze``,
    ``head_motion`` and ``seed`` (None: all on, the seed derived from the item).
    ``articulation``: a dict of ``strength``, ``scale``, ``plan`` and ``plan_iterations``
    (the command line's).
    ``phone_labels``: the phones of the TextGrid, CSV and manifest in ``ipa`` (default),
    ``arpabet`` or ``espeak`` (:func:`facemech.workflows.speak.relabel_folder`). Returns its
    :class:`~facemech.workflows.speak.Spoken`."""
    from ..atomic import check_output
    from ..errors import InputError
    from ..speech.alive import Liveliness
    from ..speech.phone_labels import LABEL_NOTATIONS
    from .speak import Recording, relabel_folder
    from .speak import speak as run

    labels = options.pop("phone_labels", None) or "ipa"
    if labels not in LABEL_NOTATIONS:
        raise InputError(f"unknown phone labels {labels!r} (expected "
                         f"{', '.join(LABEL_NOTATIONS)})", field="phone_labels")

    for k, v in (articulation or {}).items():  # the CLI's group: strength, scale, plan
        if k == "scale":
            scale = v
        else:
            options[k] = v
    if "plan_iterations" in options:  # the command line's two options, one keyword
        iterations = options.pop("plan_iterations")
        options["plan"] = iterations if options.get("plan", True) else False
    rec = {k: v for k, v in (recording or {}).items() if v is not None}
    rec.update({k: options.pop(k) for k in ("audio", "textgrid") if options.get(k) is not None})
    if options.get("tiers") is not None:
        rec["word_tier"], rec["phone_tier"] = options.pop("tiers")
    options.pop("tiers", None)
    if isinstance(alive, dict):
        alive = Liveliness(blinks=alive.get("blinks", True), gaze=alive.get("gaze", True),
                           head=alive.get("head_motion", True), seed=alive.get("seed"))
    named = [options.get(k) for k in ("face", "preset")]  # built-in names or files
    check_output(output, [rec.get("audio"), rec.get("textgrid"),
                          *(n for n in named if n and Path(str(n)).suffix)],
                 folder=True, field="-o")
    if scale:
        from ..speech.articulation import Articulation

        options["strength"] = Articulation.parse(scale, strength=options.get("strength", 1.0))
    if labels == "espeak" and rec.get("textgrid") is not None:  # before the run, not after
        from ..speech.alignment_io import read_textgrid

        if read_textgrid(rec["textgrid"], word_tier=rec.get("word_tier"),
                         phone_tier=rec.get("phone_tier")).notation != "espeak":
            raise InputError("the recording's phones cannot be written as eSpeak NG codes "
                             "(only synthesised speech has them)", source=str(rec["textgrid"]),
                             field="phone_labels")
    look = render or render_options()
    made = run(output, text, recording=Recording(**rec) if "audio" in rec else None,
               video=look if video else False, alive=alive, **options)
    return made if labels == "ipa" else relabel_folder(made, labels)


def speak_report(res, output: str | Path) -> list[str]:
    """What ``facemech speak`` prints: the phones and words, the duration and the files.

    ``res`` is the :class:`~facemech.workflows.speak.Spoken` that :func:`speak` returns.
    """
    words = " ".join(w.label for w in res.alignment.words)
    return [f"{len(res.alignment.phones)} phones ({words}), {res.alignment.duration:.2f} s "
            f"-> {output}/", *(f"  {name}: {path}" for name, path in res.files.items())]


def describe_file(result: str | Path):
    """Stimulus parameters of a results file (.nc): displacement and speed of lips, jaw and
    mouth corners, lip aperture and mouth width, the audio-visual offset, settings and input
    hashes (:class:`facemech.analysis.describe.Description`)."""
    from ..analysis.describe import describe
    from ..io.results import read_results

    return describe(read_results(result), source=str(result))


def describe_report(d, *, as_json: bool = False, series: bool = False) -> str:
    """What ``facemech describe`` prints: a table, or JSON (``series``: with the per-frame lip
    aperture and mouth width)."""
    return json.dumps(d.to_dict(series=series), indent=2) if as_json else d.table()


def describe_text(result: str | Path, *, as_json: bool = False, series: bool = False) -> str:
    """What ``facemech describe`` prints for a results file (:func:`describe_file`,
    :func:`describe_report`)."""
    return describe_report(describe_file(result), as_json=as_json, series=series)


def stimuli(design: str | Path, output: str | Path, *, video: bool = True,
            view: str = "frontal", size: str = "1280x720", background: str = "#2a2c33",
            aa: int = 2, progress=None):
    """Make the stimuli of a design table in the folder ``output``
    (:func:`facemech.workflows.stimuli.run_design`); text rows are spoken by :func:`speak` into
    ``output/items``; the movies' :func:`.pictures.render_options` are ``view``, ``size``,
    ``background``
    and ``aa``; ``progress`` is callable(stage, done, total). Returns the
    :class:`~facemech.workflows.stimuli.DesignReport`."""
    from ..atomic import check_output
    from .speak import text_items
    from .stimuli import run_design

    check_output(output, [design], folder=True, field="-o")
    return run_design(design, output, text_items(Path(output) / "items"),
                      options=render_options(view, size, background, aa), video=video,
                      progress=progress)


def stimuli_report(rep) -> tuple[list[str], list[str]]:
    """What ``facemech stimuli`` prints: (the summary lines, the failed rows' error lines)."""
    return [rep.summary()], [f"error: {e.one_line()}" for e in rep.failed]
