"""How fast the lips move under a step of full activity, for the default preset and for the
speed laws of issue 27 (an intrinsic-speed force-velocity law, the lips' measured activation
dynamics, more implicit steps): 10-90 % rise time, peak speed and creep after 300 ms.

Prints JSON. ``python benchmarks/speed.py [--face default] [--seconds 1.5] [--variants a,b]
[--overshoot] [--open-jaw]``. Each variant runs
the six perioral gestures of docs/model.md's dynamics table; the creep is how far the landmark
still moves between 300 ms after the step's 90 % point and the end, as a share of the amplitude
(the issue's limit: 5 %).
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

from facemech.params import ITO_ACTIVATION, Parameters
from facemech.physics.model import model as face_model

#: (groups, landmark, axis) of each gesture, as in benchmarks/realism.py's dynamics table
#: and the two of issue 27's speed targets: the marginal orbicularis lowering the upper lip,
#: and its lower part with mentalis raising the lower lip
GESTURES = ((("ZYG",), "mouth_corner_right", 1), (("LLS",), "upper_lip_center", 1),
            (("DLI",), "lower_lip_center", 1), (("MEN",), "chin", 1),
            (("OOS", "OOI"), "mouth_corner_right", 0), (("DAO",), "mouth_corner_right", 1),
            (("OOSM",), "upper_lip_center", 1), (("OOIM", "MEN"), "lower_lip_center", 1))

#: Ito, Murano & Gomi (2004, J Appl Physiol 96:2318): the lips' force response to a stimulus,
#: 6.1 Hz natural frequency and damping ratio 0.7
ITO = dict(ITO_ACTIVATION)
#: the seeds' force-velocity constant and activation filter (eqs. 4 and 6: f4 = 20 s/m, tau
#: 15 ms, critically damped), the defaults of ``Parameters``
SEEDS = {"fv_vmax": 0.0, "tau_activation": Parameters.tau_activation,
         "activation_damping": Parameters.activation_damping}

VARIANTS = {
    # the anatomical preset: since 2026-11-29 the laws the measured data support
    # (facemech.params: FACIAL_VMAX, LIP_ACTIVATION_TAU): 11 fibre lengths/s, eq. (4) critically
    # damped with the rise of Ito's response
    "default": {},
    # the seeds' law and filter (f4 = 20 s/m, tau 15 ms), the preset's before
    "seeds_law": SEEDS,
    "facial_vmax11_ito": {"fv_vmax": 11.0, **ITO},
    "fibre_vmax10": {"fv_vmax": 10.0, **ITO},
    "fibre_vmax20": {"fv_vmax": 20.0, **ITO},
    "fibre_vmax20_12_steps": {"fv_vmax": 20.0, **ITO, "substeps": 12},
    "no_force_velocity": {"f4": 0.0},
    # nearly incompressible tissue (Poisson's ratio 0.49 instead of 0.45): the deep prisms
    # under the nose and the chin no longer give way under full LLS and DLI (issue 27's creep)
    "poisson_049": {"poisson": 0.49},
    "poisson_049_fibre_vmax20": {"poisson": 0.49, "fv_vmax": 20.0, **ITO},
    # a floor under each prism's volume (solvers/volume_floor.py), with and without springs
    # that stiffen 4 times (not 2) beyond the knee of 15 % strain
    "fibre_vmax20_floor": {"fv_vmax": 20.0, **ITO, "volume_floor": 0.5,
                           "volume_floor_modulus": 1e6},
    "fibre_vmax20_stiffening4": {"fv_vmax": 20.0, **ITO, "stiffening": 4.0},
    "fibre_vmax20_floor_stiffening4": {"fv_vmax": 20.0, **ITO, "volume_floor": 0.5,
                                       "volume_floor_modulus": 1e6, "stiffening": 4.0},
    # the preset's measured laws with the step about its predictor solved on the true
    # linearisation (GMRES, the constant matrix its preconditioner) and Kelvin-Voigt dashpots
    **{name: {"predictor": True, "implicit_stiffness_share": 0.75, "implicit_volume_scale": 3.0,
              "dashpot_isotropy": 0.0, "krylov_iterations": 2, **extra}
       for name, extra in (("kv_krylov2", {}),
                           ("kv_krylov2_floor_stiff4", {"volume_floor": 0.5,
                                                        "volume_floor_modulus": 1e6,
                                                        "stiffening": 4.0}),
                           ("kv_krylov4_floor_stiff4", {"volume_floor": 0.5,
                                                        "volume_floor_modulus": 1e6,
                                                        "stiffening": 4.0,
                                                        "krylov_iterations": 4}),
                           ("kv_krylov4_floor_stiff4_drag50", {
                               "volume_floor": 0.5, "volume_floor_modulus": 1e6,
                               "stiffening": 4.0, "krylov_iterations": 4, "mass_drag": 50.0}),
                           ("kv_krylov4_floor_stiff4_drag200", {
                               "volume_floor": 0.5, "volume_floor_modulus": 1e6,
                               "stiffening": 4.0, "krylov_iterations": 4, "mass_drag": 200.0}),
                           ("kv_krylov4_floor_stiff4_2_steps", {
                               "volume_floor": 0.5, "volume_floor_modulus": 1e6,
                               "stiffening": 4.0, "krylov_iterations": 4, "substeps": 2}),
                           # the drag of the fast-lips preset at 2 steps per frame, 4 and 2
                           # iterations: what a step of half the cost does
                           ("kv_krylov4_floor_stiff4_drag200_2_steps", {
                               "volume_floor": 0.5, "volume_floor_modulus": 1e6,
                               "stiffening": 4.0, "krylov_iterations": 4, "mass_drag": 200.0,
                               "substeps": 2}),
                           ("kv_krylov2_floor_stiff4_drag200_2_steps", {
                               "volume_floor": 0.5, "volume_floor_modulus": 1e6,
                               "stiffening": 4.0, "mass_drag": 200.0, "substeps": 2}))},
    # the fast-lips step with its correction confined to the moving nodes within 35, 45 and
    # 60 mm of the mouth (solvers/krylov_region.py), at 4 and at 3 steps per frame, and with
    # 2 and 3 iterations
    **{f"kv_krylov{it}_floor_stiff4_drag200_region{r}{tail}": {
        "predictor": True, "implicit_stiffness_share": 0.75, "implicit_volume_scale": 3.0,
        "dashpot_isotropy": 0.0, "volume_floor": 0.5, "volume_floor_modulus": 1e6,
        "stiffening": 4.0, "mass_drag": 200.0, "krylov_iterations": it,
        "krylov_region": r * 1e-3, **extra}
       for it, r, tail, extra in ((4, 35, "", {}), (4, 45, "", {}), (4, 60, "", {}),
                                  (4, 60, "_3_steps", {"substeps": 3}),
                                  (2, 60, "", {}), (3, 60, "", {}))},
    # no force-velocity term at 4 and at 32 steps per frame: what is left is the step's drag
    # and the tissue's own slowness
    "no_force_velocity_32_steps": {"f4": 0.0, "substeps": 32},
    # the step about its explicit predictor (the matrix holding 3/4 of each stiffness and 3 x
    # the volume Gram matrices, as it must), with eq. 8's dashpots, with dashpots on the rate
    # of stretch only, and with a quarter and a half of them on eq. 8's form (docs/model.md)
    **{name: {"fv_vmax": 20.0, **ITO, "volume_floor": 0.5, "volume_floor_modulus": 1e6,
              "stiffening": 4.0, "predictor": True, "implicit_stiffness_share": 0.75,
              "implicit_volume_scale": 3.0, **extra}
       for name, extra in (("predictor", {}),
                           ("predictor_stretch_dashpots", {"dashpot_isotropy": 0.0}),
                           ("predictor_quarter_isotropic", {"dashpot_isotropy": 0.25,
                                                            "viscous_time": 4.5e-3}),
                           ("predictor_half_isotropic", {"dashpot_isotropy": 0.5,
                                                         "viscous_time": 4e-3}),
                           # the same step converging: what the Kelvin-Voigt tissue does with
                           # the matrix's added inertia 16 and 256 times smaller (docs/model.md,
                           # The step's limit)
                           ("predictor_stretch_dashpots_16_steps", {"dashpot_isotropy": 0.0,
                                                                    "substeps": 16}),
                           ("predictor_stretch_dashpots_64_steps", {"dashpot_isotropy": 0.0,
                                                                    "substeps": 64}),
                           ("predictor_stretch_dashpots_5ms_64_steps", {
                               "dashpot_isotropy": 0.0, "viscous_time": 5e-3,
                               "substeps": 64}))},
}


def measure(face, params, groups, landmark, axis, seconds):
    """Rise (s), peak speed (m/s), amplitude (m) and creep (share) of one gesture."""
    model = face_model(face, params)  # params: a preset name, Parameters or Preset
    rate = model.params.frame_rate
    from facemech.params import MUSCLE_GROUPS
    from facemech.solvers.forward import simulate

    frames = int(round(seconds * rate)) + 1
    act = np.zeros((frames, len(MUSCLE_GROUPS)))
    for g in groups:
        act[:, MUSCLE_GROUPS.index(g)] = 1.0
    sim = simulate(model, act)
    x = sim.positions[:, face.landmarks[landmark], axis]
    y = np.abs(x - x[0])
    t = np.arange(frames) / rate
    mono = np.maximum.accumulate(y)
    t10 = np.interp(0.1 * y[-1], mono, t)
    t90 = np.interp(0.9 * y[-1], mono, t)
    settled = np.interp(t90 + 0.3, t, y)
    return {"rise_ms": round(1e3 * (t90 - t10), 1),
            "peak_speed_mm_s": round(1e3 * float(np.max(np.abs(np.diff(x)))) * rate,
                                     1),
            "amplitude_mm": round(1e3 * float(y[-1]), 2),
            "creep_after_300ms": round(float((y[-1] - settled) / y[-1]), 3)}


def measure_open_jaw(face, params, groups, landmark, axis, seconds, jaw_deg=10.0):
    """:func:`measure` of a step of full activity held from 0.6 s, the jaw opened ``jaw_deg``
    degrees over the first 0.2 s (raised cosine) and held: the upper lip lowering as before a
    bilabial in speech, the lips apart (from rest they touch, and the upper lip presses on the
    lower one). Rise and speed are of the motion after the step."""
    model = face_model(face, params)  # params: a preset name, Parameters or Preset
    rate = model.params.frame_rate
    from facemech.params import MUSCLE_GROUPS
    from facemech.solvers.forward import simulate
    from facemech.waveforms import cosine_ramp

    lead = 0.6
    frames = int(round((lead + seconds) * rate)) + 1
    t = np.arange(frames) / rate
    jaw = np.deg2rad(jaw_deg) * cosine_ramp(np.clip(t / 0.2, 0.0, 1.0))
    act = np.zeros((frames, len(MUSCLE_GROUPS)))
    for g in groups:
        act[t >= lead - 1e-9, MUSCLE_GROUPS.index(g)] = 1.0
    sim = simulate(model, act, jaw)
    k0 = int(round(lead * rate))
    x = sim.positions[k0:, face.landmarks[landmark], axis]
    y = np.abs(x - x[0])
    tt = t[k0:] - t[k0]
    mono = np.maximum.accumulate(y)
    t10 = np.interp(0.1 * y[-1], mono, tt)
    t90 = np.interp(0.9 * y[-1], mono, tt)
    return {"rise_ms": round(1e3 * (t90 - t10), 1),
            "peak_speed_mm_s": round(1e3 * float(np.max(np.abs(np.diff(x)))) * rate,
                                     1),
            "amplitude_mm": round(1e3 * float(y[-1]), 2)}


def overshoot(face, params, groups, landmark, axis, seconds):
    """How far the landmark passes its rest after a 100-ms full pulse, as a share of its peak
    (tests/analysis/test_realism.py's ringing measure; its limit is 0.1)."""
    model = face_model(face, params)  # params: a preset name, Parameters or Preset
    rate = model.params.frame_rate
    from facemech.params import MUSCLE_GROUPS
    from facemech.solvers.forward import simulate

    act = np.zeros((int(round(seconds * rate)), len(MUSCLE_GROUPS)))
    for g in groups:
        act[:int(round(0.1 * rate)), MUSCLE_GROUPS.index(g)] = 1.0
    x = simulate(model, act).positions[:, face.landmarks[landmark], axis]
    x = x - x[0]
    x = x * np.sign(x[np.argmax(np.abs(x))])
    k = int(np.argmax(x))
    return round(float(max(0.0, -x[k:].min()) / x[k]), 3)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--face", default="default")
    ap.add_argument("--seconds", type=float, default=1.5)
    ap.add_argument("--variants", default=",".join(VARIANTS))
    ap.add_argument("--overshoot", action="store_true",
                    help="also the overshoot past rest after a 100-ms full pulse (twice the time)")
    ap.add_argument("--open-jaw", action="store_true",
                    help="also OOSM lowering the upper lip with the jaw open 10 degrees")
    args = ap.parse_args(argv)
    from threadpoolctl import threadpool_limits

    from facemech import default_face
    from facemech.errors import SimulationBlowUp
    from facemech.params import preset_pair

    face = default_face(args.face)
    out = {"face": args.face, "seconds": args.seconds, "variants": {}}
    with threadpool_limits(1):
        for name in args.variants.split(","):
            p = preset_pair("anatomical").with_(**VARIANTS[name])
            rows = {}
            t0 = time.perf_counter()
            for groups, landmark, axis in GESTURES:
                try:
                    rows["+".join(groups)] = measure(face, p, groups, landmark, axis,
                                                     args.seconds)
                    if args.overshoot:
                        rows["+".join(groups)]["overshoot_after_pulse"] = overshoot(
                            face, p, groups, landmark, axis, args.seconds)
                except SimulationBlowUp as exc:  # a variant that blows up is a result too
                    rows["+".join(groups)] = {"blew_up": str(exc)}
                print(f"{name} {'+'.join(groups)} {rows['+'.join(groups)]}", file=sys.stderr,
                      flush=True)
            if args.open_jaw:
                try:
                    rows["OOSM, jaw open 10 deg"] = measure_open_jaw(
                        face, p, ("OOSM",), "upper_lip_center", 1, args.seconds)
                except SimulationBlowUp as exc:
                    rows["OOSM, jaw open 10 deg"] = {"blew_up": str(exc)}
                print(f"{name} OOSM, jaw open {rows['OOSM, jaw open 10 deg']}", file=sys.stderr,
                      flush=True)
            out["variants"][name] = {"changes": {k: float(v) for k, v in VARIANTS[name].items()},
                                     "wall_s": round(time.perf_counter() - t0, 1),
                                     "gestures": rows}
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
