"""The input groups of ``simulate``, ``invert``, ``speak``, ``analyse`` and ``markers``, each
declared once (:mod:`facemech.inputs`): the command line's options, the batch manifest's keys
and the workflows' Python signatures are made from these dataclasses (the jaw's groups:
:mod:`facemech.jaw.inputs`; the fit's: :mod:`facemech.inverse.options`). Pure Python: the
command line imports it for ``--help``."""

from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path

from ..checks import check_value
from ..errors import InputError
from ..inputs import REQUIRED, option

__all__ = ["LOWPASS_HZ", "Alive", "Analysis", "Bounds", "Controls", "MarkerFile",
           "MarkerReading", "Preparation", "PresetChoice", "Recording", "Speaking", "Stepping"]

#: Hz, the default low-pass of a recording: speech movements lie below it (lip and jaw
#: kinematics have little energy above 10 Hz; a 12-15 Hz cut-off is usual for marker data)
LOWPASS_HZ = 12.0


@dataclass(frozen=True)
class Controls:
    """Where the muscle input comes from: exactly one of ``activity`` (a CSV, time and muscle
    groups in [0, 1]) and ``emg`` (raw EMG, CSV or C3D, the seeds' seven channels), with the
    EMG's rest interval ``emg_baseline`` (start, stop) s and a calibration recording of maximal
    gestures ``emg_calibration`` (its channels those of ``emg``)."""

    activity: Path | None = option(None, "activity CSV")
    emg: Path | None = option(None, "raw EMG (CSV or C3D), 7 channels")
    emg_baseline: str | tuple[float, float] | None = option(
        None, "EMG rest interval START,STOP (s)", unit="s", cli=str | None)
    emg_calibration: Path | None = option(None, "EMG of maximal gestures")

    def __post_init__(self):
        if (self.activity is None) == (self.emg is None):
            raise InputError("give exactly one of --activity and --emg", field="activity")


@dataclass(frozen=True)
class Stepping:
    """How a simulation steps (None: the preset's): the jaw's kinematics (``hinge`` or
    ``glide``), the integrator (``euler``, ``implicit`` or ``rosenbrock``), the steps per frame
    of the implicit integrators, the explicit Euler step ``dt`` (s) and the jaw's drive within
    a frame (``ramp`` or ``hold``), as :func:`facemech.solvers.forward.simulate` takes them."""

    jaw_kinematics: str | None = option(None, "hinge or glide")
    integrator: str | None = option(None, "euler, implicit or rosenbrock")
    substeps: int | None = option(None, "steps per frame (implicit)")
    dt: float | None = option(None, "explicit Euler step, s", unit="s")
    jaw_drive: str = option("ramp", "ramp or hold")

    def solver_options(self) -> dict:
        """The options of :func:`facemech.solvers.forward.simulate` (all but the kinematics)."""
        return {f.name: getattr(self, f.name) for f in fields(self) if f.name != "jaw_kinematics"}


@dataclass(frozen=True)
class MarkerFile:
    """The marker file of an inversion and how its markers are laid on the face.

    Attributes
    ----------
    path : marker file: motion capture in the model's frame and at its frame rate, or
        articulography (resampled, its lips laid on the face's vermilion points)
    units : length unit of a file that carries none
    map_file : marker,node CSV (default: the closest nodes)
    scale_pair : "A,B": adapt the markers by per-axis scaling from two markers far apart
    """

    path: Path = option(REQUIRED, "mocap in the model's frame and rate, or articulography "
                        "(.ema .est .txy), resampled", key="markers")
    units: str | None = option(None, "length unit if the file has none")
    map_file: Path | None = option(None, "marker,node CSV (default: closest nodes)",
                                   flags=("--map",))
    scale_pair: str | None = option(None, "A,B: scale the markers per axis")


@dataclass(frozen=True)
class PresetChoice:
    """The preset of an inversion (a name or a preset ``.json``) with a command's overrides: the
    jaw's kinematics (``hinge`` or ``glide``) and the explicit Euler step ``dt`` (s) of every
    evaluation (its method's ``fast_dt``)."""

    preset: str = option("anatomical", "anatomical, lucero1999, pitermann2001, calibrated or a "
                         "preset .json", kind="file_or_name")
    jaw_kinematics: str | None = option(None, "hinge or glide (or the preset's)")
    dt: float | None = option(None, "Euler step of every evaluation, s (default: the "
                              "preset's)", unit="s")

    def resolve(self):
        """The :class:`~facemech.params.Preset` with the overrides."""
        from ..params import Preset, preset_pair

        params, steps = preset_pair(self.preset)
        if self.jaw_kinematics is not None:
            params = params.with_(jaw_kinematics=self.jaw_kinematics)
        return Preset(params, steps if self.dt is None else steps.with_(fast_dt=self.dt))


@dataclass(frozen=True)
class Recording:
    """A recorded voice and its alignment (``speak``).

    Attributes
    ----------
    audio : the WAV (None: no recording, the text is synthesised)
    textgrid : its Praat TextGrid (e.g. from the Montreal Forced Aligner)
    word_tier, phone_tier : the TextGrid's tier names (None: found by name, as MFA writes them)
    """

    audio: str | Path | None = option(None, "a recorded voice (WAV) to speak with",
                                      cli=Path | None)
    textgrid: str | Path | None = option(None, "the recording's Praat TextGrid (MFA)",
                                         cli=Path | None)
    word_tier: str | None = option(None, "TextGrid tier name (default: found by name)")
    phone_tier: str | None = option(None, "the same, phones")


@dataclass(frozen=True)
class Speaking:
    """How ``speak`` speaks and what it writes.

    Attributes
    ----------
    voice, rate_wpm : eSpeak NG voice (e.g. ``en-us``, ``en-gb+f3``) and words per minute
    strength : scale of every viseme's departure from rest (1 = the table's), or a
        :class:`facemech.speech.articulation.Articulation`
    scale : rules ``KIND:KEY=FACTOR`` scaling one phone, word or viseme class (a list, or one
        string, rules separated by ``;``)
    plan, plan_iterations : plan the controls for the face's dynamics, with that many
        iterations (0-20, each one more simulation; ``plan=False``: the dominance blend)
    phone_labels : the phones written: ``ipa``, ``arpabet`` or ``espeak``
    video : render the MP4 with the audio
    """

    voice: str = option("en-us", "eSpeak NG voice, e.g. en-us, en-gb, en-us+f3")
    rate_wpm: int = option(160, "words per minute", unit="1/min", flags=("--rate",))
    strength: float = option(1.0, "scale of the visemes' departure from rest")
    scale: tuple[str, ...] | str | None = option(
        None, "KIND:KEY=FACTOR (repeatable), e.g. word:balloon=1.5, class:open=0.8, "
        "phone:u:=1.2", cli=list[str] | None, kind="str")
    plan: bool = option(True, "plan the controls for the face's dynamics (--no-plan: the "
                        "dominance blend as it is)")
    plan_iterations: int = option(8, "the planner's iterations, each one more simulation "
                                  "(0-20)")
    phone_labels: str = option("ipa", "phone labels written: ipa, arpabet or espeak "
                               "(eSpeak's codes)")
    video: bool = option(True, "render the MP4")

    def articulation(self):
        """The :class:`~facemech.speech.articulation.Articulation`: ``strength`` with the
        ``scale`` rules."""
        from ..speech.articulation import Articulation, as_articulation

        if not self.scale:
            return as_articulation(self.strength)
        return Articulation.parse(self.scale if isinstance(self.scale, str) else
                                  list(self.scale), strength=self.strength)

    def iterations(self):
        """The planner's iterations (False: not planned), as ``speak``'s ``plan`` takes it."""
        return self.plan_iterations if self.plan else False

    @classmethod
    def from_keywords(cls, base: Speaking | None = None, **keywords) -> Speaking:
        """``base`` (default: the defaults) with the fields given as keywords; ``plan`` may be a
        number of iterations (``speak``'s keyword), ``video`` a render's options (kept True)."""
        from dataclasses import replace

        plan = keywords.get("plan")
        if plan is not None and not isinstance(plan, bool):
            keywords.update(plan=True, plan_iterations=plan)
        if "video" in keywords and not isinstance(keywords["video"], bool):
            keywords["video"] = keywords["video"] is not None
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(keywords) - names)
        if unknown:
            raise TypeError(f"unexpected keyword {unknown[0]!r}")
        return replace(base or cls(), **keywords)


@dataclass(frozen=True)
class Alive:
    """What makes the spoken face alive (``speak``): blinks, gaze shifts and head motion, each
    on or off, and the seed of their random schedules (None: derived from the item)."""

    blinks: bool = option(True, "blinks at the rate of conversation (26/min)")
    gaze: bool = option(True, "small gaze shifts, about one a second")
    head_motion: bool = option(True, "head motion driven by the voice's F0 and level")
    seed: int | None = option(None, "seed of the blinks, gaze shifts and head motion "
                              "(default: from the item)")

    def liveliness(self):
        """The :class:`facemech.speech.alive.Liveliness` of these choices."""
        from ..speech.alive import Liveliness

        return Liveliness(blinks=self.blinks, gaze=self.gaze, head=self.head_motion,
                          seed=self.seed)


@dataclass(frozen=True)
class Preparation:
    """How ``analyse`` prepares a recording: the length unit of a recording that carries
    none, the longest gap filled (s) and the low-pass cut-off (Hz; None or 0: none)."""

    units: str | None = option(None, "length unit if the file has none")
    max_gap: float = option(0.1, "longest gap to fill, s", unit="s")
    lowpass: float | None = option(LOWPASS_HZ, "low-pass cut-off of the recording, Hz (0: "
                                   "none)", unit="Hz")

    def __post_init__(self):  # the command line's intervals (facemech.checks)
        check_value("max_gap", self.max_gap)
        if self.lowpass is not None:
            check_value("lowpass", self.lowpass)


@dataclass(frozen=True)
class Analysis:
    """How ``analyse`` inverts a recording: the method (``lsq`` or ``powell``), the controls
    (``speech``, ``emg7``, ``all`` or listed groups), the marker noise of the standard errors
    (mm; None: from the residuals), the lsq fit's window (frames) and smoothness weight
    (mm/unit), longer and stronger than the method's own (2, 0.3) as a recording is noisy
    (docs/recordings.md), and the movie."""

    method: str = option("lsq", "lsq (fast) or powell (the seeds')")
    controls: str = option("speech", "speech, emg7, all, or listed groups (default: speech, "
                           "or what the markers determine)")
    noise: float | None = option(None, "marker noise for the SEs, mm (or fit)", unit="mm")
    window: int | None = option(3, "lsq: frames fitted per frame", unit="frames")
    smooth: float | None = option(1.0, "lsq: smoothness weight, mm/unit", unit="mm")
    video: bool = option(False, "also render movie.mp4")

    def inversion(self):
        """The :class:`~facemech.inverse.options.InversionOptions` of the inversion."""
        from ..inverse.options import InversionOptions

        return InversionOptions(self.method, controls=self.controls, noise=self.noise)

    def fit_options(self) -> dict:
        """The method's options: lsq's window and smoothness, none for powell."""
        return {"window": self.window, "smooth": self.smooth} if self.method == "lsq" else {}


@dataclass(frozen=True)
class MarkerReading:
    """How a marker file that does not say them is read: its rate (Hz) and its sensors' names
    in channel order, comma-separated (:func:`facemech.io.markers.read_markers`)."""

    rate: float | None = option(None, "Hz, for files without times (AG500 .pos: 200; MOCHA "
                                "20-column text: 500)", unit="Hz")
    sensors: str | None = option(None, "sensor names in channel order, e.g. ul,ll,li (.pos, "
                                 "NDI Wave)")

    def options(self) -> dict:
        """The keywords of :func:`facemech.io.markers.read_markers`."""
        return {"rate": self.rate, "sensors": self.sensors}


@dataclass(frozen=True)
class Bounds:
    """The frames ``markers trim`` keeps: between two times (s, the file's own) or two frame
    numbers (from 0, as ``markers info`` shows them); none: the empty ends dropped."""

    start: float | None = option(None, "keep from this time, s (the file's times)", unit="s")
    stop: float | None = option(None, "keep up to this time, s", unit="s")
    first: int | None = option(None, "keep from this frame (from 0, as markers info shows)")
    last: int | None = option(None, "keep up to this frame")

    def given(self) -> bool:
        """Whether any bound is given."""
        return any(v is not None for v in (self.start, self.stop, self.first, self.last))
