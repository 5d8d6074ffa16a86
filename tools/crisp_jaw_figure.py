"""Draw docs/img/crisp-jaw.png: a sentence with few labials planned without and with the speed
target (issue 29's speed; docs/visible-speech.md, "A slow sentence gets a crisper jaw"): the
jaw's angle, the lower incisor's speed and the lower lip's speed over time, with the phones.

``python tools/crisp_jaw_figure.py [--text "..."] [-o docs/img/crisp-jaw.png]`` (about a
minute: two plans of the sentence on the default face).
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

#: a Harvard sentence (IEEE 1969, list 1) without a labial: its lower lip rides the jaw
TEXT = "These days a chicken leg is a rare dish."


def _spoken(text: str, speed: bool):
    """(time s, jaw deg, incisor speed mm/s, lower-lip speed mm/s, alignment) of ``text``
    said as ``facemech speak`` says it (eSpeak en-us, 175 words a minute, planned), with the
    plan's speed target or (``speed`` False) without it."""
    from unittest import mock

    from facemech.speech import planning
    from facemech.speech.alive import Liveliness
    from facemech.speech.visible_speech import incisor_speed, lower_lip_speed
    from facemech.workflows.speak import speak

    off = {"SPEED_COST": 0.0, "GAIN": {**planning.GAIN, "speed_jaw_rate": 0.0}}
    on = {"SPEED_COST": planning.SPEED_COST, "GAIN": planning.GAIN}
    with tempfile.TemporaryDirectory() as tmp, \
            mock.patch.multiple(planning, **(on if speed else off)):
        sp = speak(tmp, text, rate_wpm=175, video=False, alive=Liveliness.off())
    sim = sp.simulation
    return (sim.time, np.degrees(sim.jaw_pose[:, 0]),
            1e3 * incisor_speed(sim.time, sim.jaw_pose, sim.model),
            1e3 * lower_lip_speed(sim.time, sim.positions, sim.model), sp.alignment)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--text", default=TEXT)
    ap.add_argument("-o", "--output", type=Path,
                    default=Path(__file__).resolve().parent.parent / "docs/img/crisp-jaw.png")
    args = ap.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from facemech.atomic import atomic_path

    runs = {"planned without the speed target": _spoken(args.text, False),
            "planned now: the jaw crisper, stressed vowels opened": _spoken(args.text, True)}
    fig, axes = plt.subplots(3, 1, figsize=(9, 7.5), sharex=True)
    for (label, (t, jaw, inc, lip, _)), style in zip(runs.items(), ("--", "-"), strict=True):
        axes[0].plot(t, jaw, style, label=label)
        axes[1].plot(t, inc, style, label=f"{label}: peak {inc.max():.0f} mm/s")
        axes[2].plot(t, lip, style, label=f"{label}: peak {lip.max():.0f} mm/s")
    for y, what in ((186.0, "fastest real jaw (issue 27)"), (58.0, "slowest real jaw")):
        axes[1].axhline(y, color="grey", lw=0.8, ls=":")
        axes[1].text(0.01, y + 3, what, color="grey", fontsize=8)
    axes[2].axhspan(100.0, 250.0, color="tab:green", alpha=0.12, lw=0)
    axes[2].text(0.01, 104, "issue 29: 100-250 mm/s", color="tab:green", fontsize=8)
    alignment = next(iter(runs.values()))[4]
    for seg in alignment.phones:
        if seg.label in ("_", ""):
            continue
        mid = 0.5 * (seg.start + seg.end)
        axes[0].axvline(seg.start, color="0.85", lw=0.6, zorder=0)
        axes[0].text(mid, 0.3, seg.label, ha="center", fontsize=7)
    axes[0].set_ylabel("jaw angle (deg)")
    axes[1].set_ylabel("lower incisor speed (mm/s)")
    axes[2].set_ylabel("lower lip speed (mm/s)")
    axes[2].set_xlabel("time (s)")
    top = max(r[1].max() for r in runs.values())
    axes[0].set_ylim(0.0, 1.4 * top)  # room for the legend above the jaw's peaks
    for ax in axes:
        ax.legend(fontsize=8, loc="upper right")
    axes[0].set_title(f'"{args.text}" (eSpeak en-us, 175 wpm, default face)', fontsize=10)
    fig.tight_layout()
    args.output.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(args.output) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    print(args.output)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
