"""Where does the reachability error come from? Prints JSON (each variant takes minutes).

The synthetic speech targets of :mod:`facemech.analysis.reachability` (issue 27: upper lip 3 mm
down and 3 mm front-back, lower lip 9 and 4.5 mm, 6 mm of it on the jaw, at up to 118 mm/s),
inverted with the jaw from the lower incisor, under variants that each change one cause:

- ``default``: as the test and ``benchmarks/realism.py`` run it;
- ``slowed_4x``: the same path, postures and transitions 4 times longer (lower lip at up to
  30 mm/s): what is left is reach (a posture out of the face's range), not speed;
- ``speech_controls``, ``all_controls``: the control set (without the marginal orbicularis; every
  group of the face);
- ``window_3``, ``window_4``, ``no_smoothing``: the inversion's settings (look-ahead of the
  receding horizon, the first- and second-difference weights);
- ``fast_muscles``: the muscle dynamics the physics is moving to (force-velocity Vmax 20 fibre
  lengths/s, the activation filter of Ito et al. 2004 at 6.1 Hz and damping 0.7, 12 steps per
  frame), with ``fast_muscles_window_4`` and ``fast_muscles_slowed_4x`` (the reach left under
  them).

docs/model.md (Reachability) has the measured table.

Each variant reports the RMS (mm), the largest error, each component's RMS and share of the
squared error (:data:`facemech.analysis.reachability.COMPONENTS`; ``lower_lip_on_jaw_vertical``
is relative to the incisor), the share of controls on a bound and the wall time.

Usage: python benchmarks/reachability.py [--variants default,slowed_4x,...] [--face default]
"""

from __future__ import annotations

import argparse
import json
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from facemech.physics.model import model as face_model

#: Ito, Murano & Gomi (2004): the lips' force response, 6.1 Hz, damping ratio 0.7
FAST = {"fv_vmax": 20.0, "tau_activation": 1.0 / (2.0 * np.pi * 6.1),
        "activation_damping": 0.7, "substeps": 12, "dt": 1.0 / 720.0, "fast_dt": 1.0 / 720.0}

#: variant -> (slowing factor, controls or None for the reach set, inversion options, params)
VARIANTS = {
    "default": (1.0, None, {}, {}),
    "slowed_4x": (4.0, None, {}, {}),
    "speech_controls": (1.0, "speech", {}, {}),
    "all_controls": (1.0, "all", {}, {}),
    "window_3": (1.0, None, {"window": 3}, {}),
    "window_4": (1.0, None, {"window": 4}, {}),
    "no_smoothing": (1.0, None, {"smooth": 0.0, "bend": 0.0}, {}),
    "fast_muscles": (1.0, None, {}, FAST),
    "fast_muscles_window_4": (1.0, None, {"window": 4}, FAST),
    "fast_muscles_slowed_4x": (4.0, None, {}, FAST),
}


def run(face, name: str) -> dict:
    """One variant's numbers (mm, s)."""
    from facemech.analysis.reachability import REACH_CONTROLS, reach, speech_targets
    from facemech.params import preset

    slow, controls, options, changes = VARIANTS[name]
    params = preset("anatomical").with_(**changes)
    ms = speech_targets(face, posture_s=0.16 * slow, transition_s=0.12 * slow,
                        frame_rate=params.frame_rate)
    r = reach(face_model(face, params), markers=ms, controls=controls or REACH_CONTROLS, **options)
    return {"rms_mm": round(r.rms * 1e3, 3), "largest_mm": round(r.largest * 1e3, 2),
            "components_rms_mm": {k: round(v * 1e3, 3) for k, v in r.components.items()},
            "share_of_squared_error": {k: round(v, 3) for k, v in r.share.items()},
            "controls_on_a_bound": round(r.activity_on_bound, 2),
            "wall_s": round(r.wall_seconds, 1)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--face", default="default")
    ap.add_argument("--variants", default=",".join(VARIANTS))
    args = ap.parse_args(argv)
    from facemech import default_face

    face = default_face(args.face)
    t0 = time.perf_counter()
    out = {"face": args.face, "target_rms_mm": 0.5, "variants": {}}
    for name in args.variants.split(","):
        out["variants"][name] = run(face, name)
    out["wall_s"] = round(time.perf_counter() - t0, 1)
    print(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
