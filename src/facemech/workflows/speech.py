"""``facemech speak``, ``describe`` and ``stimuli``: a talking face from text or a recording,
the stimulus parameters of a result, and the stimuli of a design table."""

from __future__ import annotations

import json
from pathlib import Path

from .pictures import render_options

__all__ = ["describe_file", "describe_report", "describe_text", "speak",
           "speak_report", "stimuli", "stimuli_report"]


def speak(output: str | Path, text: str | None = None, *, speaking=None, recording=None,
          alive=None, render=None, **options):
    """Make the face say ``text``, or speak in sync with a recorded voice, into the folder
    ``output`` (what ``facemech speak`` does): :func:`facemech.workflows.speak.speak` with the
    command's input groups (:mod:`facemech.workflows.inputs`): ``speaking``
    (:class:`~.inputs.Speaking`: voice, rate, articulation, plan, phone labels, video),
    ``recording`` (:class:`~.inputs.Recording`) and ``alive`` (:class:`~.inputs.Alive`, or a
    :class:`facemech.speech.alive.Liveliness`), the movie drawn with ``render`` (a
    :class:`facemech.viz.video.RenderOptions`, :func:`.pictures.render_options`; None:
    frontal+profile, 1280x720). ``options``: ``face``, ``preset``, ``progress`` and the fields
    of :class:`~.inputs.Speaking` as keywords; the older forms are taken too: ``recording``,
    ``alive`` or ``articulation`` as dicts, ``audio``, ``textgrid`` and ``tiers`` (word,
    phone). Checks the output against the inputs first. Returns its
    :class:`~facemech.workflows.speak.Spoken`."""
    from ..atomic import check_output
    from .inputs import Recording, Speaking
    from .speak import speak as run

    recording, alive, options = _older_forms(recording, alive, options)
    keys = {f for f in Speaking.__dataclass_fields__ if f in options}
    speaking = Speaking.from_keywords(speaking, **{k: options.pop(k) for k in keys})
    recording = recording or Recording()
    named = [options.get(k) for k in ("face", "preset")]  # built-in names or files
    check_output(output, [recording.audio, recording.textgrid,
                          *(n for n in named if n and Path(str(n)).suffix)],
                 folder=True, field="-o")
    return run(output, text, recording=recording if recording.audio is not None else None,
               speaking=speaking, video=(render or render_options()) if speaking.video
               else False, alive=alive, **options)


def _older_forms(recording, alive, options: dict):
    """``speak``'s older keywords as its input groups: ``recording`` and ``alive`` as dicts,
    ``audio``, ``textgrid`` and ``tiers``, and ``articulation`` (a dict of ``strength``,
    ``scale``, ``plan``, ``plan_iterations``) into ``options``."""
    from .inputs import Alive, Recording

    options = dict(options)
    options.update(options.pop("articulation", None) or {})
    rec = {k: v for k, v in (recording or {}).items() if v is not None} \
        if isinstance(recording, dict) else {}
    rec.update({k: options.pop(k) for k in ("audio", "textgrid") if k in options
                and options[k] is not None})
    options.pop("audio", None), options.pop("textgrid", None)
    tiers = options.pop("tiers", None)
    if tiers is not None:
        rec["word_tier"], rec["phone_tier"] = tiers
    if isinstance(recording, dict) or rec:
        recording = Recording(**{**({} if isinstance(recording, dict) or recording is None
                                    else vars(recording)), **rec})
    if isinstance(alive, dict):
        alive = Alive(**alive)
    return recording, alive, options


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
