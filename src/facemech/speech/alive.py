"""A face that is alive: blinks, small gaze shifts and head motion driven by the voice.

Per-frame series for a talking face (:func:`liveliness`), from the utterance's audio, its frame
times and a seed; deterministic given the seed. The physics does not see them: the simulation
stays in the head's frame, the renderer turns the whole head (:meth:`facemech.viz.scene.Scene.
frame`), so the stimulus parameters stay relative to the head. Everything is SI: s, rad, Hz.

- blinks (:func:`blink_schedule`, :func:`blink_closure`): :data:`BLINK_RATE_PER_MIN` (26/min in
  conversation, Bentivoglio et al. 1997), gamma intervals after a refractory one, each blink
  three raised-cosine phases, closing faster than opening (VanderWerf et al. 2003);
- gaze (:func:`gaze_schedule`, :func:`gaze_series`): fixations and small saccades of
  ``21 ms + 2.2 ms/deg`` (the main sequence, Carpenter 1988; Baloh et al. 1975), minimum jerk;
- head (:func:`head_motion`): pitch follows the voice's F0 (Yehia et al. 2002; Munhall et al.
  2004), smoothed and leading it; yaw and roll wander with the voice's level.

:class:`Liveliness` holds the switches, the seed and the blink rate; :func:`laws` lists the
constants, as the manifest records them. Sources and choices: docs/stimuli.md, "A face that
is alive".
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..checks import check_fields, check_value
from ..errors import InputError
from .pitch import PRAAT_AC, intensity_db, track_f0

__all__ = ["Alive", "Liveliness", "blink_closure", "blink_schedule", "gaze_schedule",
           "gaze_series", "head_motion", "item_seed", "laws", "liveliness"]

#: blinks per minute during conversation (Bentivoglio et al. 1997: 26.0 mean)
BLINK_RATE_PER_MIN = 26.0
#: s, the shortest interval between two blinks' onsets (our choice)
BLINK_MIN_INTERVAL_S = 0.5
#: shape of the gamma variate added to the minimum interval (our choice)
BLINK_INTERVAL_SHAPE = 2.0
#: s, the lid's closing, closed and opening phases (closing faster than opening)
BLINK_CLOSE_S, BLINK_HOLD_S, BLINK_OPEN_S = 0.08, 0.02, 0.17
#: s, the mean and the shortest fixation between two gaze shifts (our choices)
GAZE_MEAN_INTERVAL_S, GAZE_MIN_INTERVAL_S = 1.2, 0.4
#: rad, SD of the gaze targets' yaw and pitch about straight ahead, and their bound (2, 1.5, 5 deg)
GAZE_SD_RAD = (np.radians(2.0), np.radians(1.5))
GAZE_MAX_RAD = np.radians(5.0)
#: s and s/rad, the saccade's main sequence: duration = intercept + slope * amplitude
SACCADE_INTERCEPT_S, SACCADE_SLOPE_S_PER_RAD = 0.021, 0.0022 * np.degrees(1.0)
#: rad of head pitch (up) per semitone of F0 above the median (0.8 deg): a sentence's F0
#: spans some 4-8 semitones, so the head nods over 3-6 degrees, the few degrees of rotation
#: that accompany read speech (Yehia et al. 2002; Munhall et al. 2004; Hadar et al. 1983)
HEAD_PITCH_PER_SEMITONE_RAD = np.radians(0.8)
#: rad, the head pitch's bound either way (6 deg)
HEAD_MAX_RAD = np.radians(6.0)
#: s, the head pitch leads F0 by this much
HEAD_LEAD_S = 0.1
#: s, the SD of the Gaussian that smooths the head's drive
HEAD_SMOOTH_S = 0.08
#: rad, SD of the yaw and the roll at full voice (1.6, 0.9 deg), s their noise's smoothing
HEAD_YAW_RAD, HEAD_ROLL_RAD, HEAD_WANDER_SD_S = np.radians(1.6), np.radians(0.9), 0.4
#: dB, the range below the loudest frame over which the intensity scales the wander (0..1)
HEAD_LEVEL_RANGE_DB = 30.0


@dataclass(frozen=True)
class Liveliness:
    """What makes the face alive, each on or off, and the seed of the random schedules.

    Attributes
    ----------
    blinks, gaze, head : blinks, gaze shifts, head motion (driven by the voice)
    seed : the random generator's seed (``numpy.random.default_rng``); None: derived from the
        item (:func:`item_seed` of its audio), so that each item blinks, looks and moves in
        its own way and says it again the same way
    blink_rate_per_min : blinks per minute, (0, 60] (default: in conversation, Bentivoglio 1997)
    """

    blinks: bool = True
    gaze: bool = True
    head: bool = True
    seed: int | None = None
    blink_rate_per_min: float = BLINK_RATE_PER_MIN

    def __post_init__(self):
        if self.seed is None:
            check_value("blink_rate_per_min", self.blink_rate_per_min)
        else:
            check_fields(self)  # seed and blink rate: the intervals of facemech.checks
            object.__setattr__(self, "seed", int(self.seed))
        object.__setattr__(self, "blink_rate_per_min", float(self.blink_rate_per_min))

    @classmethod
    def off(cls) -> Liveliness:
        """Nothing moves but the speech."""
        return cls(blinks=False, gaze=False, head=False)


def item_seed(samples, sample_rate: float) -> int:
    """A seed in [0, 2**32) derived from an item's audio (its samples as 16-bit PCM, and the
    rate): the same item gets the same seed, two items almost surely different ones."""
    import hashlib

    pcm = np.round(np.clip(np.asarray(samples, float), -1.0, 1.0) * 32767).astype("<i2")
    h = hashlib.sha256(pcm.tobytes() + str(int(sample_rate)).encode())
    return int.from_bytes(h.digest()[:4], "little")


def _blink_length() -> float:
    return BLINK_CLOSE_S + BLINK_HOLD_S + BLINK_OPEN_S


def laws(alive: Liveliness) -> dict:
    """The settings (``settings``) and the laws' constants (``blink``, ``gaze``, ``head``,
    ``sources``), as the manifest records them (SI)."""
    return {"settings": asdict(alive),
            "blink": {"rate_per_min": alive.blink_rate_per_min,
                      "min_interval_s": BLINK_MIN_INTERVAL_S,
                      "interval_gamma_shape": BLINK_INTERVAL_SHAPE,
                      "close_s": BLINK_CLOSE_S, "hold_s": BLINK_HOLD_S,
                      "open_s": BLINK_OPEN_S},
            "gaze": {"mean_interval_s": GAZE_MEAN_INTERVAL_S,
                     "min_interval_s": GAZE_MIN_INTERVAL_S,
                     "sd_rad": [float(v) for v in GAZE_SD_RAD], "max_rad": float(GAZE_MAX_RAD),
                     "saccade_intercept_s": SACCADE_INTERCEPT_S,
                     "saccade_slope_s_per_rad": float(SACCADE_SLOPE_S_PER_RAD)},
            "head": {"pitch_per_semitone_rad": float(HEAD_PITCH_PER_SEMITONE_RAD),
                     "max_rad": float(HEAD_MAX_RAD), "lead_s": HEAD_LEAD_S,
                     "smooth_s": HEAD_SMOOTH_S, "yaw_sd_rad": float(HEAD_YAW_RAD),
                     "roll_sd_rad": float(HEAD_ROLL_RAD), "wander_s": HEAD_WANDER_SD_S,
                     "level_range_db": HEAD_LEVEL_RANGE_DB,
                     "f0_praat_ac": dict(PRAAT_AC)},
            "sources": ["Bentivoglio et al. 1997 Mov Disord 12:1028",
                        "VanderWerf et al. 2003 J Neurophysiol 89:2784",
                        "Carpenter 1988 Movements of the Eyes",
                        "Yehia, Kuratate & Vatikiotis-Bateson 2002 J Phonetics 30:555",
                        "Munhall et al. 2004 Psychol Sci 15:133",
                        "Hadar et al. 1983 Lang Speech 26:117",
                        "Boersma 1993 Proc Inst Phonetic Sci Amsterdam 17:97"]}


def _intervals(rng, duration: float, mean: float, minimum: float, shape: float,
               first: float) -> np.ndarray:
    """Onset times in [0, duration): ``first`` * a uniform variate, then minimum + gamma."""
    scale = (mean - minimum) / shape
    times, t = [], first * rng.uniform()
    while t < duration:
        times.append(t)
        t += minimum + rng.gamma(shape, scale)
    return np.array(times)


def blink_schedule(duration: float, rng, rate_per_min: float = BLINK_RATE_PER_MIN) -> np.ndarray:
    """Blink onsets (s) in [0, duration): a renewal process of mean interval 60 / rate.

    Parameters
    ----------
    duration : s
    rng : ``numpy.random.Generator``
    rate_per_min : blinks per minute

    Returns
    -------
    (B,) s, increasing; every interval at least :data:`BLINK_MIN_INTERVAL_S`
    """
    mean = 60.0 / rate_per_min
    return _intervals(rng, duration, mean, BLINK_MIN_INTERVAL_S, BLINK_INTERVAL_SHAPE, mean)


def blink_closure(time, onsets) -> np.ndarray:
    """Lid closure (0 open .. 1 closed) at ``time`` (s) of blinks starting at ``onsets`` (s).

    Each blink closes over :data:`BLINK_CLOSE_S`, holds :data:`BLINK_HOLD_S` and opens over
    :data:`BLINK_OPEN_S` (raised-cosine ramps). Returns (T,).
    """
    t = np.asarray(time, float)
    out = np.zeros_like(t)
    for t0 in np.asarray(onsets, float):
        u = t - t0
        close = np.clip(u / BLINK_CLOSE_S, 0.0, 1.0)
        opening = np.clip((u - BLINK_CLOSE_S - BLINK_HOLD_S) / BLINK_OPEN_S, 0.0, 1.0)
        b = 0.5 - 0.5 * np.cos(np.pi * close)
        b = np.where(opening > 0, 0.5 + 0.5 * np.cos(np.pi * opening), b)
        b[(u < 0) | (u >= _blink_length())] = 0.0
        out = np.maximum(out, b)
    return out


def gaze_schedule(duration: float, rng) -> tuple[np.ndarray, np.ndarray]:
    """Gaze shifts in [0, duration): (onsets (S,) s, targets (S, 2) rad (yaw, pitch)).

    The gaze starts straight ahead; each shift goes to a target drawn about straight ahead.
    """
    onsets = _intervals(rng, duration, GAZE_MEAN_INTERVAL_S, GAZE_MIN_INTERVAL_S, 2.0,
                        GAZE_MEAN_INTERVAL_S)
    targets = rng.normal(0.0, 1.0, (len(onsets), 2)) * np.asarray(GAZE_SD_RAD)
    return onsets, np.clip(targets, -GAZE_MAX_RAD, GAZE_MAX_RAD)


def saccade_duration(amplitude_rad) -> np.ndarray:
    """s, the main sequence: 21 ms + 2.2 ms per degree (Carpenter 1988)."""
    return SACCADE_INTERCEPT_S + SACCADE_SLOPE_S_PER_RAD * np.asarray(amplitude_rad, float)


def gaze_series(time, onsets, targets) -> np.ndarray:
    """(T, 2) rad, (yaw, pitch) at ``time``: minimum-jerk saccades from each fixation to the
    next target, starting at ``onsets`` (s), straight ahead before the first."""
    t = np.asarray(time, float)
    out = np.zeros((len(t), 2))
    here = np.zeros(2)
    for t0, goal in zip(np.asarray(onsets, float), np.asarray(targets, float), strict=True):
        d = float(saccade_duration(np.linalg.norm(goal - here)))
        s = np.clip((t - t0) / d, 0.0, 1.0)[:, None]
        jerk = s ** 3 * (10 - 15 * s + 6 * s ** 2)
        after = t >= t0
        out[after] = (here + (goal - here) * jerk)[after]
        here = goal
    return out


def _gauss(x: np.ndarray, sd_frames: float) -> np.ndarray:
    from scipy.ndimage import gaussian_filter1d

    return gaussian_filter1d(x, sd_frames, mode="nearest") if sd_frames > 0 else x


def head_motion(time, samples, sample_rate: float, rng) -> tuple[np.ndarray, dict]:
    """Head rotation (T, 3) rad (pitch up, yaw to the subject's left, roll to the left) driven
    by the voice, and its summary.

    Parameters
    ----------
    time : (T,) s, evenly spaced frame times
    samples : (n,) float, the audio (full scale 1)
    sample_rate : Hz
    rng : ``numpy.random.Generator`` (the yaw and roll's noise)

    Returns
    -------
    (T, 3) rad, and a dict: the F0 tracker (``f0_method``), the track's median (Hz) and
    voiced fraction, each angle's peak
    and SD (rad), the correlation of the pitch with F0 (semitones, voiced frames) at the lead,
    and the lead (s)
    """
    t = np.asarray(time, float)
    dt = float(t[1] - t[0]) if len(t) > 1 else 1.0
    track = track_f0(samples, sample_rate, t)
    level = intensity_db(samples, sample_rate, t)
    pose = np.zeros((len(t), 3))
    summary = {"f0_method": track.method, "f0_median_hz": None,
               "voiced_fraction": float(track.voiced.mean()),
               "lead_s": HEAD_LEAD_S}
    if track.voiced.sum() >= 2:
        f0_med = float(np.median(track.f0[track.voiced]))
        st = 12.0 * np.log2(np.where(track.voiced, track.f0, f0_med) / f0_med)
        k = np.flatnonzero(track.voiced)
        held = np.interp(np.arange(len(t)), k, st[k])  # across unvoiced stretches
        voicing = _gauss(track.voiced.astype(float), HEAD_SMOOTH_S / dt)
        drive = _gauss(held * voicing, HEAD_SMOOTH_S / dt)
        lead = HEAD_LEAD_S / dt
        pitch = np.interp(np.arange(len(t)) + lead, np.arange(len(t)), drive)  # earlier
        pose[:, 0] = np.clip(HEAD_PITCH_PER_SEMITONE_RAD * pitch, -HEAD_MAX_RAD, HEAD_MAX_RAD)
        summary["f0_median_hz"] = f0_med
        n = int(round(lead))
        a, b = pose[: len(t) - n, 0], st[n:]
        v = track.voiced[n:]
        if v.sum() > 2 and np.std(a[v]) > 0 and np.std(b[v]) > 0:
            summary["pitch_f0_correlation"] = float(np.corrcoef(a[v], b[v])[0, 1])
    loud = np.clip((level - level.max() + HEAD_LEVEL_RANGE_DB) / HEAD_LEVEL_RANGE_DB, 0, 1)
    loud = _gauss(loud, HEAD_SMOOTH_S / dt)
    for axis, sd in ((1, HEAD_YAW_RAD), (2, HEAD_ROLL_RAD)):
        sd_frames = HEAD_WANDER_SD_S / dt
        # unit SD: white noise smoothed by a Gaussian of SD s frames has SD (2 sqrt(pi) s)^-1/2
        noise = _gauss(rng.normal(size=len(t)), sd_frames) * np.sqrt(2 * np.sqrt(np.pi)
                                                                      * sd_frames)
        pose[:, axis] = np.clip(sd * noise * loud, -HEAD_MAX_RAD, HEAD_MAX_RAD)
    for i, name in enumerate(("pitch", "yaw", "roll")):
        summary[f"{name}_peak_rad"] = float(np.abs(pose[:, i]).max(initial=0.0))
        summary[f"{name}_sd_rad"] = float(np.std(pose[:, i])) if len(t) else 0.0
    return pose, summary


@dataclass(frozen=True)
class Alive:
    """The per-frame series of :func:`liveliness` and what made them.

    Attributes
    ----------
    time : (T,) s
    blink : (T,) closure 0..1
    gaze : (T, 2) rad, (yaw, pitch)
    head : (T, 3) rad, (pitch, yaw, roll) about the head's pivot
    blinks : (B, 2) s, each blink's onset and duration
    gaze_shifts : (S, 3) onset s, target yaw and pitch rad
    head_summary : dict (:func:`head_motion`)
    settings : the :class:`Liveliness`, its seed the one used
    seed_derived : the seed was derived from the item (:func:`item_seed`), not given
    """

    time: np.ndarray
    blink: np.ndarray
    gaze: np.ndarray
    head: np.ndarray
    blinks: np.ndarray
    gaze_shifts: np.ndarray
    head_summary: dict
    settings: Liveliness
    seed_derived: bool = False

    def record(self) -> dict:
        """What the manifest records: the settings and laws, blink times, gaze shifts and the
        head motion's summary and series (SI)."""
        return {"laws": laws(self.settings),
                "seed": {"value": self.settings.seed,
                         "source": "derived from the item's audio" if self.seed_derived
                         else "given"},
                "blinks": [{"onset_s": float(a), "duration_s": float(d)} for a, d in self.blinks],
                "gaze_shifts": [{"onset_s": float(a), "yaw_rad": float(y), "pitch_rad": float(p)}
                                for a, y, p in self.gaze_shifts],
                "head": {**self.head_summary, "on": self.settings.head,
                         "series_rad": {"pitch": self.head[:, 0].tolist(),
                                        "yaw": self.head[:, 1].tolist(),
                                        "roll": self.head[:, 2].tolist()}}}


def liveliness(time, samples, sample_rate: float, alive: Liveliness | None = None) -> Alive:
    """Blinks, gaze and head motion for an utterance, at its frame times.

    Parameters
    ----------
    time : (T,) s, evenly spaced frame times (the simulation's)
    samples : (n,) float, the utterance's audio (full scale 1), starting at time 0
    sample_rate : Hz
    alive : switches, seed and blink rate (default: everything on, the seed derived from
        ``samples``, :func:`item_seed`)

    Returns
    -------
    Alive; a switched-off part's series are zeros and its events empty
    """
    alive = alive or Liveliness()
    if alive.seed is None:
        from dataclasses import replace

        alive = replace(alive, seed=item_seed(samples, sample_rate))
        derived = True
    else:
        derived = False
    t = np.asarray(time, float)
    if t.ndim != 1 or len(t) == 0 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise InputError("frame times must be a finite, increasing (T,) series", field="time")
    duration = float(t[-1]) + (float(t[1] - t[0]) if len(t) > 1 else 0.0)
    # one generator per part: switching one off does not change the others
    rngs = [np.random.default_rng([alive.seed, k]) for k in range(3)]
    onsets = blink_schedule(duration, rngs[0], alive.blink_rate_per_min) if alive.blinks \
        else np.zeros(0)
    blink = blink_closure(t, onsets)
    shifts, targets = gaze_schedule(duration, rngs[1]) if alive.gaze \
        else (np.zeros(0), np.zeros((0, 2)))
    gaze = gaze_series(t, shifts, targets)
    if alive.head:
        head, summary = head_motion(t, samples, sample_rate, rngs[2])
    else:
        head, summary = np.zeros((len(t), 3)), {}
    return Alive(time=t, blink=blink, gaze=gaze, head=head,
                 blinks=np.column_stack([onsets, np.full(len(onsets), _blink_length())])
                 .reshape(-1, 2),
                 gaze_shifts=np.column_stack([shifts, targets]).reshape(-1, 3),
                 head_summary=summary, settings=alive, seed_derived=derived)
