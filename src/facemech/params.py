"""Biomechanical parameters and the two published presets.

Values are SI; the comment beside each field gives the paper's CGS value (Lucero & Munhall 1999,
Tables I-II and section I; Pitermann & Munhall 2001 for the second damping value).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from .checks import check_fields
from .errors import InputError
from .stepping import PRESET_STEPS, StepOptions, split_overrides
from .units import CM, DYNE, GRAM

#: Muscle groups of the model, in the order used for activity arrays.
MUSCLE_GROUPS: tuple[str, ...] = (
    "DAO", "DLI", "LAO", "ZYG", "LLS", "MEN", "OOS", "OOI",
    "ZMI", "RIS", "LLSAN", "COR", "CSU", "FRM", "FRL", "FRI", "OOSM", "OOIM",
)  # fmt: skip
#: The marginal part of orbicularis oris (upper, lower lip): built only on the anatomical tissue
#: (:data:`facemech.geometry.anatomy.MARGINAL`); the seeds' faces have no muscle of these groups
MARGINAL_GROUPS: tuple[str, ...] = ("OOSM", "OOIM")

#: The seven EMG control channels of the seeds (LAO and ZYG share one signal).
EMG_CHANNELS: tuple[str, ...] = ("LLS", "LAO", "DAO", "DLI", "MEN", "OOS", "OOI")
#: Hz, the control and output frame rate of every preset (the seeds' 60-Hz Optotrak rate); the
#: one default of every frame rate in facemech
FRAME_RATE_HZ = 60.0

# Cross-sectional areas S in cm^2.  The eight perioral values are Table II of Lucero & Munhall
# (1999).  The paper lists the other muscles without an area; our estimates scale each by its size
# relative to a Table II muscle of similar build:
#   ZMI   0.10  a thin strap like zygomatic major (0.10)
#   RIS   0.05  the thinnest perioral muscle, a fan of a few fascicles: half of ZYG
#   LLSAN 0.10  thinner than LLS (0.15), as its medial slip is shared with the nose
#   COR   0.15  corrugator: a short thick muscle, like LLS
#   CSU   0.10  its superficial slip
#   FRM   0.40  frontalis, central belly: a broad sheet, like DAO (0.40)
#   FRL   0.20  lateral frontalis: half of the central belly
#   FRI   0.20  inner frontalis
#   OOSM, OOIM 0.20  the marginal part of orbicularis oris in each lip: a third of Table II's
#               0.60 for the whole muscle of a lip, a bundle about 5 mm high and 4 mm thick in
#               the red lip near its free margin (our estimate; with it the part lowers the
#               upper lip 3.6 mm and lifts the lower lip 6.6 mm on the jaw, docs/model.md)
AREA_CM2 = MappingProxyType({
    "ZYG": 0.10, "LLS": 0.15, "DAO": 0.40, "DLI": 0.11, "MEN": 0.07, "LAO": 0.10,
    "OOS": 0.60, "OOI": 0.60,
    "ZMI": 0.10, "RIS": 0.05, "LLSAN": 0.10, "COR": 0.15, "CSU": 0.10,
    "FRM": 0.40, "FRL": 0.20, "FRI": 0.20, "OOSM": 0.20, "OOIM": 0.20,
})  # fmt: skip


#: Areas of the anatomical preset, cm^2: Table II (Kennedy & Abbs 1979, via Lucero & Munhall
#: 1999) where it has them, except zygomatic major, taken from its measured size: 8.5 mm wide
#: (51 cadavers, Stoltidou et al. 2011) by about 2.2 mm thick (1.5-3 mm, the perioral muscles by
#: ultrasound, van Alfen et al. 2013), 0.19 cm^2; and risorius, a thin fan (our estimate: about
#: 15 mm wide and 1 mm thick at the modiolus, 0.15 cm^2; the muscle is variable and sometimes
#: absent). Table II's 0.10 cm^2 for zygomatic major is about half its measured size.
ANATOMICAL_AREA_CM2 = MappingProxyType({**AREA_CM2, "ZYG": 0.19, "RIS": 0.15})

#: How a jaw angle alone moves the mandible: ``"hinge"`` (the seeds: a rotation about the
#: condyles) or ``"glide"`` (the rotation plus the condyle's coupled glide forward and down along
#: the articular eminence, :func:`facemech.solvers.jaw.condyle_glide`).
JAW_KINEMATICS = ("hinge", "glide")
#: m of condyle travel per radian of jaw opening, calibrated on the default face so that its
#: lower incisor moves 3.6 mm back at a 22-mm drop, as in a real recording of speech (X-ray
#: microbeam, repeated "sa": 22 mm down, 3.6 mm front to back; docs/model.md): the
#: fit is 28.4 mm/rad, rounded to 28 (3.7 mm)
GLIDE_RATE = 0.028
#: rad below the horizontal of the condyle's path: 35 degrees, a typical inclination of the
#: articular eminence
GLIDE_SLOPE = float(np.radians(35.0))


@dataclass(frozen=True)
class Parameters:
    """Constants of the face model (SI units), checked when made: every field's kind, interval
    or choices (:mod:`facemech.checks`; ``Parameters(material="contnuum")`` is an InputError
    naming ``material``), the jaw's kinematics and the muscle dynamics.

    All spring stiffnesses are for a 1-cm spring; a spring of rest length ``l0`` gets
    ``k = k_ref * (1 cm / l0)`` (Lucero & Munhall 1999, section I.A).
    """

    name: str = "lucero1999"
    node_mass: float = 0.23 * GRAM  # kg (0.23 g)
    damping: float = 30 * DYNE / CM  # N s/m (30 dyne s/cm)
    k_epidermis: float = 1200 * DYNE / CM  # N/m for a 1-cm spring (1200 dyne/cm)
    k_fascia: float = 600 * DYNE / CM  # N/m (600 dyne/cm)
    k_muscle_layer: float = 600 * DYNE / CM  # N/m (600 dyne/cm)
    k_dermal_low: float = 600 * DYNE / CM  # N/m, k1 of eq. (1)
    k_dermal_high: float = 6000 * DYNE / CM  # N/m, k2 of eq. (1)
    biphasic_knee: float = 0.2  # strain at which eq. (1) switches from k1 to k2
    sigma: float = 0.98  # compression factor of eq. (2)
    spring_ref_length: float = 1 * CM  # m, the length the k_* values are given for
    depth_fascia: float = 1.5e-3  # m, epidermis -> fascia
    depth_skull: float = 2.5e-3  # m, fascia -> skull
    k_force: float = 2500 * DYNE / CM**2  # N/m^2, k_f of eq. (3) (2500 dyne/cm^2)
    tau_activation: float = 0.015  # s, tau of eq. (4)
    f1: float = 0.82  # eq. (6)
    f2: float = 0.5  # eq. (6)
    f3: float = 0.43  # eq. (6)
    f4: float = 0.2 / CM  # s/m, eq. (6) (0.2 s/cm)
    # fibre lengths per second: when > 0, each muscle's f4 of eq. (6) comes from this intrinsic
    # speed and its fibre length (physics/muscle.py: fibre_f4) instead of ``f4``; 0: the seeds'
    fv_vmax: float = 0.0
    fv_curvature: float = 0.25  # a/F0 of Hill's hyperbola that places eq. (6)'s half force
    activation_damping: float = 1.0  # damping ratio of eq. (4)'s filter (1: the seeds')
    k_passive_per_cm2: float = 17300 * DYNE / CM  # N/m per cm^2 of area (17 300 dyne/cm)
    k_volume: float = 1000 * DYNE / CM**3  # N/m^3, k_e1 of eq. (9) (1000 dyne/cm^3)
    k_shape: float = 2000 * DYNE / CM  # N/m, k_e2 of eq. (9) (2000 dyne/cm)
    k_restore: float = 200 * DYNE / CM  # N/m, k_h of eq. (11) (200 dyne/cm)
    k_lip_contact: float = 50.0  # N/m, penalty stiffness that keeps the lips apart (our choice)
    frame_rate: float = FRAME_RATE_HZ  # Hz, control and output rate
    areas_cm2: MappingProxyType = field(default_factory=lambda: AREA_CM2)
    # ---- how the constants above are read, and what the anatomical preset adds ---------------
    # "per_spring": the seeds' constants per 1-cm spring and per node (Lucero & Munhall 1999);
    # "continuum": moduli, density and viscosity of tissue, turned into spring constants and
    # node masses by the volume of the elements around them (physics/materials.py)
    material: str = "per_spring"
    tissue: str = "uniform"  # tissue geometry of the face: "uniform" (the seeds') or "anatomical"
    density: float = 1050.0  # kg/m^3, soft tissue (continuum)
    shear_superficial: float = 0.0  # Pa, shear modulus between skin and muscle plane (continuum)
    shear_deep: float = 0.0  # Pa, shear modulus between muscle plane and bone (continuum)
    lip_stiffness_factor: float = 1.0  # continuum: moduli in the lips / elsewhere
    poisson: float = 0.45  # Poisson's ratio of the tissue (continuum; the volume term supplies
    # what the springs, whose lattice has 1/4, lack)
    skin_modulus_thickness: float = 0.0  # N/m, Young's modulus x thickness of the dermis
    viscous_time: float = 0.0  # s, tissue viscosity / modulus (stiffness-proportional damping)
    #: continuum: the share of each spring's dashpot on the whole relative velocity of its ends
    #: (1: eq. 8's form); the rest damps the rate of stretch only (a Kelvin-Voigt solid's
    #: viscosity), which does not resist a rigid turn of the tissue (the lower lip
    #: everts as a nearly rigid flap, and eq. 8's dashpots made it slow)
    dashpot_isotropy: float = 1.0
    # continuum: strain stiffening, the stiffness of every spring times this beyond
    # ``biphasic_knee`` of stretch (eq. 1's law on all springs; 1: linear)
    stiffening: float = 1.0
    fixed_skull_contact: bool = True  # eq. (10) on the tied fascia (the seeds')
    sphincter_scale: float = 1.0  # force of the sphincters (OOS, OOI) relative to eq. (3)
    tether: float = 0.0  # N/m^3, stiffness per area holding the sliding deep surface (continuum)
    incisive_area_cm2: float = 0.10  # cm^2, each incisive bundle of orbicularis oris (estimate)
    k_bone_contact: float = 0.0  # N/m^3, one-sided contact of the sliding surface with the bone
    # how a jaw angle alone moves the mandible (JAW_KINEMATICS): the seeds' hinge, or the hinge
    # with the condyle's coupled glide of glide_rate (m/rad) along glide_slope (rad below the
    # horizontal)
    jaw_kinematics: str = "hinge"
    glide_rate: float = GLIDE_RATE
    glide_slope: float = GLIDE_SLOPE

    def __post_init__(self):
        check_fields(self)  # kinds, intervals and choices: the one table of facemech.checks
        check_jaw_kinematics(self.jaw_kinematics, self.glide_rate, self.glide_slope)
        check_muscle_dynamics(self.fv_vmax, self.fv_curvature, self.tau_activation,
                              self.activation_damping)

    @property
    def is_continuum(self) -> bool:
        """Constants are tissue moduli (the anatomical preset), not per-spring values."""
        return self.material == "continuum"

    def instance_area(self, name: str, group: str) -> float:
        """Cross-sectional area (m^2) of one muscle instance: its group's, or for the incisive
        bundles of orbicularis oris :data:`INCISIVE_AREA_CM2`."""
        if "incisive" in name:
            return self.incisive_area_cm2 * CM**2
        return self.muscle_area(group)

    def muscle_area(self, group: str) -> float:
        """Cross-sectional area of a muscle group in m^2 (times ``sphincter_scale`` for the
        sphincters: the force of eq. (3) is k_f times this)."""
        scale = self.sphincter_scale if group in ("OOS", "OOI") else 1.0
        return self.areas_cm2[group] * CM**2 * scale

    def passive_stiffness(self, group: str) -> float:
        """Passive muscle stiffness k_m of eq. (7) in N/m (17.3 N/m per cm^2 of area); none for
        orbicularis oris's marginal part, whose passive tissue is the red lip's own (the
        continuum's lip moduli), so that the part is inert at rest."""
        if group in MARGINAL_GROUPS:
            return 0.0
        return self.k_passive_per_cm2 * self.areas_cm2[group]

    def with_(self, **changes) -> Parameters:
        """A copy with some fields changed."""
        return replace(self, **changes)


def _is_number(v) -> bool:
    """A finite real scalar (not a bool or a string)."""
    if isinstance(v, (bool, str)) or np.ndim(v) != 0:
        return False
    try:
        return bool(np.isreal(v) and np.isfinite(v))
    except TypeError:
        return False


def check_jaw_kinematics(kinematics, rate, slope, *, source: str | None = None) -> None:
    """Validate a preset's jaw kinematics: InputError naming the field."""
    if kinematics not in JAW_KINEMATICS:
        raise InputError(f"unknown jaw kinematics {kinematics!r} (expected "
                         f"{' or '.join(JAW_KINEMATICS)})", source=source,
                         field="jaw_kinematics")
    if not (_is_number(rate) and 0 <= rate <= 0.1):
        raise InputError(f"glide rate must be between 0 and 100 mm/rad (got {rate!r} m/rad)",
                         source=source, field="glide_rate")
    if not (_is_number(slope) and -np.pi / 2 <= slope <= np.pi / 2):
        raise InputError(f"glide slope must be between -90 and 90 degrees (got {slope!r} rad)",
                         source=source, field="glide_slope")


#: the muscle-dynamics entries of a preset file's ``muscle`` block: key -> (Parameters field,
#: factor from the file's unit to SI)
MUSCLE_DYNAMICS_KEYS = MappingProxyType({
    "fv_vmax_fibre_lengths_per_s": ("fv_vmax", 1.0),
    "fv_curvature": ("fv_curvature", 1.0),
    "activation_tau_ms": ("tau_activation", 1e-3),
    "activation_damping": ("activation_damping", 1.0),
})


def check_muscle_dynamics(vmax, curvature, tau, zeta, *, source: str | None = None) -> None:
    """Validate the force-velocity and activation constants: InputError naming the field.

    ``vmax`` (fibre lengths per second, 0 for the seeds' absolute f4) in [0, 100];
    ``curvature`` (a/F0 of Hill's hyperbola) in (0, 10]; ``tau`` (s) in (0, 1];
    ``zeta`` (damping ratio of eq. 4) in (0, 1].
    """
    checks = (("fv_vmax", vmax, 0.0, 100.0, True, "fibre lengths per second"),
              ("fv_curvature", curvature, 0.0, 10.0, False, ""),
              ("tau_activation", tau, 0.0, 1.0, False, "s"),
              ("activation_damping", zeta, 0.0, 1.0, False, ""))
    for name, v, lo, hi, closed, unit in checks:
        ok = _is_number(v) and (lo <= v if closed else lo < v) and v <= hi
        if not ok:
            low = "[" if closed else "("
            raise InputError(f"{name} must be a number in {low}{lo:g}, {hi:g}]"
                             f"{' ' + unit if unit else ''} (got {v!r})", source=source,
                             field=name)


def preset(name: str) -> Parameters:
    """Return a parameter preset by name, or one saved by ``facemech calibrate`` (a JSON file).

    Parameters
    ----------
    name : {"anatomical", "lucero1999", "pitermann2001", "calibrated"} or a path to a ``.json``
        ``anatomical`` (the default) is the resolution-consistent tissue of physiological
        constants whose few global scales are calibrated to gesture amplitudes of real faces
        (:func:`anatomical`); ``lucero1999`` uses the published constants with damping
        r = 30 dyne s/cm (Lucero & Munhall 1999); ``pitermann2001`` uses r = 0.050 kg/s
        (Pitermann & Munhall 2001); ``calibrated`` is ``lucero1999`` with the muscle force
        scale k_f re-selected for the generic face (:data:`CALIBRATED_K_FORCE`).
    """
    name = str(name)
    if name == "anatomical":
        return anatomical()
    if name == "lucero1999":
        return Parameters()
    if name == "pitermann2001":
        return Parameters(name="pitermann2001", damping=0.050)
    if name == "calibrated":
        return Parameters(name="calibrated", k_force=CALIBRATED_K_FORCE)
    if name.lower().endswith(".json"):
        return read_preset(name)
    raise InputError(f"unknown preset {name!r} (expected {', '.join(PRESETS)} or a .json "
                     "file written by facemech calibrate)", field="preset")


#: k_f of eq. (3) re-selected for the generic face (N/m^2): 16 x 2500 dyne/cm^2. Lucero & Munhall
#: chose k_f "according to the results of the animations" on their mesh; on ours the published
#: value moves Experiment 1 of Pitermann & Munhall (2001) by 0.22 mm against their 2.02 mm, and
#: 16 times it moves it by 1.99 mm (paper integrator, 0.33-ms Euler steps; docs/model.md).
CALIBRATED_K_FORCE = 16 * 2500 * DYNE / CM**2

#: Specific tension of human skeletal muscle in vivo, N/m^2: 26.8 N/cm^2, the weighted mean of
#: a systematic review of 96 values (Persad et al. 2024, J Appl Physiol 137:945); Powell et al.
#: (1984, J Appl Physiol 57:1715) found 22.5 N/cm^2, Narici et al. (1992) about 25 N/cm^2.
SPECIFIC_TENSION = 26.8 * 1e4

#: Intrinsic speed of the facial muscles' fibres, fibre lengths per second (``fv_vmax`` of the
#: anatomical preset; docs/model.md, Speed laws). Human muscle is modelled at 10
#: (Zajac 1989, Crit Rev Biomed Eng 17:359), taken here as that of a limb muscle of 42 % type I
#: fibres (gracilis 36 %, rectus femoris 48 %), scaled by the mimic muscles' larger share of
#: fast fibres measured in the same cadavers: zygomaticus major, levator labii superioris,
#: levator and depressor anguli oris 27-38 % type I (Happak et al. 1988, J Neurol Sci 83:25;
#: orbicularis oris has 66-73 % fast fibres, as a study of the eyelid's fibre types reports beside
#: the orbicularis oculi's 88 %). A muscle's speed mixes its fibres' as ``s_I + r (1 - s_I)`` for
#: fast fibres ``r`` times as fast as slow ones: 1.09-1.12 times the limb muscle's for r = 3-5,
#: and at most 0.68 / 0.58 = 1.17 for any r. Hence 11.
FACIAL_VMAX = 11.0
#: Activation dynamics of the anatomical preset (the perioral muscles'): eq. (4)'s
#: critically damped filter, its tau chosen so that its 10-90 % rise (55.5 ms) equals that of
#: the lips' measured force response to a stimulus, second order at 6.1 Hz with damping ratio
#: 0.7 (orbicularis oris superior 0.71, inferior 0.68; eight subjects, Ito, Murano & Gomi 2004,
#: J Appl Physiol 96:2318). The measured damping itself (tau 26.1 ms, zeta 0.7:
#: :data:`ITO_ACTIVATION`), tried as the default, left the dynamic inversion's three-frame
#: window blind to part of the activity (docs/model.md). The 14.5-15.6 ms delay is left out
#: (an inversion's activity absorbs it as a lead).
LIP_ACTIVATION_TAU = 16.5e-3
LIP_ACTIVATION_DAMPING = 1.0
#: The lips' measured activation response as eq. (4) with a damping ratio (Ito et al. 2004)
ITO_ACTIVATION = MappingProxyType({"tau_activation": 1.0 / (2.0 * np.pi * 6.1),
                                   "activation_damping": 0.7})

#: The two global scales of the anatomical preset fitted to the gesture targets of docs/model.md
#: (``facemech calibrate --builtin``, analysis/calibration.py): the muscle force as a factor on
#: the specific tension (fitted 1.28, rounded up to leave risorius a margin on its 3-mm target:
#: 34.8 N/cm^2) and the moduli of the lips relative to the rest of the tissue (fitted 3.11).
FITTED_FORCE = 1.30
FITTED_LIPS = 3.1

#: Scales of the anatomical preset a calibration can change (factors on the values above;
#: ``facemech calibrate`` fits force and lips by default).
ANATOMICAL_SCALES = MappingProxyType({
    "force": 1.0,  # x SPECIFIC_TENSION
    "stiffness": 1.0,  # x the shear moduli of both layers
    "lips": 1.0,  # moduli in the lips relative to elsewhere
    "sphincter": 1.0,  # x the force of orbicularis oris's chain through the lips
})


def anatomical(scales: dict | None = None) -> Parameters:
    """The anatomical preset, optionally with other global scales (see :data:`ANATOMICAL_SCALES`).

    Constants and their sources (docs/model.md has the full table):

    - muscle force: eq. (3) with k_f the specific tension of muscle (26.8 N/cm^2, Persad et al.
      2024) times ``scales["force"]``, and the cross-sectional areas of Table II of Lucero &
      Munhall (1999), from Kennedy & Abbs (1979);
    - tissue: shear moduli 6 kPa between the skin and the muscle plane and 1.5 kPa under it
      (Young's moduli of 17 and 4.4 kPa at Poisson's ratio 0.45), times ``scales["stiffness"]``:
      relaxed zygomaticus major measures about 15 kPa by shear-wave elastography (Ternifi et al.
      2019), buccinator 4-17 kPa (Stepanova et al. 2023), face soft tissue 31-42 kPa by
      aspiration of the skin (Luboz et al. 2014), which includes the dermis; the dermis is a
      membrane of Young's modulus x thickness 100 N/m (about 70 kPa over its 1-2 mm, Chopra et
      al. 2015 for the thickness);
    - density 1050 kg/m^3 (muscle 1050, skin 1100, fat 950: ICRU 46 / White et al. 1987);
    - viscosity: a viscous time (viscosity / modulus) of 3 ms (no published facial-tissue
      viscosity serves): small enough not to slow gestures, large enough for the step's stability
      (docs/model.md);
    - muscle speed: eq. (6)'s force-velocity term per muscle from an intrinsic speed of
      :data:`FACIAL_VMAX` = 11 fibre lengths per second (Zajac 1989 scaled by the facial
      muscles' fibre types, Happak et al. 1988) and each muscle's fibre length; eq. (4)'s
      critically damped filter with tau :data:`LIP_ACTIVATION_TAU` = 16.5 ms, whose 10-90 %
      rise is that of the lips' measured force response (55.5 ms; Ito, Murano & Gomi 2004).
      The seeds' f4 = 20 s/m and tau = 15 ms stay in their presets;
    The preset's numerical method (linearly implicit Euler, 4 steps per frame, the contacts
    stepped after each solve) is :data:`facemech.stepping.PRESET_STEPS`.
    """
    s = {**ANATOMICAL_SCALES, **(scales or {})}
    unknown = set(s) - set(ANATOMICAL_SCALES)
    if unknown:
        raise InputError(f"unknown scale {sorted(unknown)[0]!r} (expected "
                         f"{', '.join(ANATOMICAL_SCALES)})", field="scales")
    for k, v in s.items():
        if not (np.isfinite(v) and v > 0):
            raise InputError(f"scale {k!r} must be a positive number (got {v!r})",
                             field=k or "scales")
    return Parameters(
        name="anatomical", material="continuum", tissue="anatomical",
        k_force=SPECIFIC_TENSION * FITTED_FORCE * s["force"],
        shear_superficial=6e3 * s["stiffness"], shear_deep=1.5e3 * s["stiffness"],
        lip_stiffness_factor=FITTED_LIPS * s["lips"], sphincter_scale=0.05 * s["sphincter"],
        poisson=0.45, skin_modulus_thickness=100.0,
        viscous_time=3e-3, density=1050.0,
        stiffening=2.0, biphasic_knee=0.15,
        damping=0.0, node_mass=0.0, k_epidermis=0.0, k_fascia=0.0, k_muscle_layer=0.0,
        k_dermal_low=0.0, k_dermal_high=0.0, sigma=0.0, k_volume=0.0, k_shape=0.0,
        k_restore=0.0, k_lip_contact=1e5, fixed_skull_contact=False,
        areas_cm2=ANATOMICAL_AREA_CM2, incisive_area_cm2=0.25, tether=0.0,
        k_bone_contact=1e7, jaw_kinematics="glide", glide_rate=GLIDE_RATE,
        glide_slope=GLIDE_SLOPE,
        fv_vmax=FACIAL_VMAX, tau_activation=LIP_ACTIVATION_TAU,
        activation_damping=LIP_ACTIVATION_DAMPING,
    )


def read_preset(path) -> Parameters:
    """A preset saved by :func:`write_preset` (``facemech calibrate``): JSON with the base preset
    and the scales fitted to a subject (its step options: :func:`read_preset_steps`)."""
    return _read_preset_file(path)[0]


def read_preset_steps(path) -> StepOptions:
    """The :class:`~facemech.stepping.StepOptions` of a preset file: the base preset's with the
    file's ``step`` block."""
    return _read_preset_file(path)[1]


def _read_preset_file(path) -> tuple[Parameters, StepOptions]:
    import json
    from pathlib import Path

    path = Path(path)
    if not path.is_file():
        raise InputError("file not found", source=str(path))
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, UnicodeDecodeError):
        raise InputError("not a JSON preset file", source=str(path)) from None
    except RecursionError:
        raise InputError("not a JSON preset file (nested too deeply)", source=str(path)) from None
    if not isinstance(data, dict) or data.get("format") != "facemech-preset":
        raise InputError("not a facemech preset file", source=str(path), field="format")
    if data.get("base") != "anatomical":
        raise InputError("only presets based on 'anatomical' can be read", source=str(path),
                         field="base")
    scales = data.get("scales")
    if not isinstance(scales, dict):
        raise InputError("missing scales", source=str(path), field="scales")
    for key, v in scales.items():
        if _file_number(v) is None:
            raise InputError(f"scale {key!r} must be a positive number (got {v!r})",
                             source=str(path), field=key or "scales")
    try:
        p = anatomical({k: _file_number(v) for k, v in scales.items()})
    except InputError as exc:
        raise InputError(exc.message, source=str(path), field=exc.field) from None
    base_steps = PRESET_STEPS["anatomical"]
    tissue, steps = _read_step(data.get("step"), p, base_steps, str(path))
    return (p.with_(name=str(data.get("name", path.stem)),
                    **_read_jaw(data.get("jaw"), p, str(path)),
                    **_read_muscle(data.get("muscle"), p, str(path)), **tissue),
            base_steps.with_(**steps))


def _file_number(v) -> float | None:
    """A preset file's number as a finite float; None for anything else (a boolean, text, an
    integer beyond a float's range, NaN, an infinity)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return None
    try:
        x = float(v)
    except OverflowError:
        return None
    return x if np.isfinite(x) else None


#: a preset file's ``step`` block: the file's key -> (the field, its kind and the factor to
#: SI): the step's options (:class:`~facemech.stepping.StepOptions`) and the tissue's viscosity
#: and stiffening (:class:`Parameters`)
STEP_KEYS = MappingProxyType({
    "substeps": ("substeps", int, 1),
    "predictor": ("predictor", bool, 1),
    "krylov_iterations": ("krylov_iterations", int, 1),
    "krylov_region_mm": ("krylov_region", float, 1e-3),
    "mass_drag_per_s": ("mass_drag", float, 1.0),
    "implicit_stiffness_share": ("implicit_stiffness_share", float, 1.0),
    "implicit_volume_scale": ("implicit_volume_scale", float, 1.0),
    "dashpot_isotropy": ("dashpot_isotropy", float, 1.0),
    "viscous_time_ms": ("viscous_time", float, 1e-3),
    "stiffening": ("stiffening", float, 1.0),
    "volume_floor": ("volume_floor", float, 1.0),
    "volume_floor_modulus_pa": ("volume_floor_modulus", float, 1.0),
})


def _read_step(block, base: Parameters, steps: StepOptions, source: str) -> tuple[dict, dict]:
    """The tissue and step options of a preset file's ``step`` block (absent: the base
    preset's; :data:`STEP_KEYS`), as changes to the parameters and to the step options, checked
    as a whole: a bad entry is an InputError naming the file and ``step.KEY``."""
    if block is None:
        return {}, {}
    if not isinstance(block, dict):
        raise InputError("step must be an object", source=source, field="step")
    unknown = sorted(set(block) - set(STEP_KEYS))
    if unknown:
        raise InputError(f"unknown step entry {unknown[0]!r} (expected "
                         f"{', '.join(STEP_KEYS)})", source=source, field="step." + unknown[0])
    out = {}
    for key, v in block.items():
        name, kind, scale = STEP_KEYS[key]
        number = _file_number(v)
        if (kind is bool and not isinstance(v, bool)) or (kind is not bool and number is None) or (
                kind is int and not float(number).is_integer()):
            raise InputError(f"{key} must be {'true or false' if kind is bool else 'a number'}"
                             f"{' of steps' if kind is int else ''} (got {v!r})", source=source,
                             field="step." + key)
        out[name] = v if kind is bool else kind(number) * scale
    method, tissue = split_overrides(out)
    try:
        base.with_(**tissue)
        steps.with_(**method)
    except InputError as exc:
        key = next((k for k, (f, _, _) in STEP_KEYS.items() if f == exc.field), None)
        raise InputError(exc.message, source=source,
                         field="step." + key if key else "step") from None
    return tissue, method


def _read_muscle(block, base: Parameters, source: str) -> dict:
    """The muscle dynamics of a preset file's ``muscle`` block (absent: the base preset's):
    ``fv_vmax_fibre_lengths_per_s``, ``fv_curvature``, ``activation_tau_ms``,
    ``activation_damping`` (:data:`MUSCLE_DYNAMICS_KEYS`)."""
    if block is None:
        return {}
    if not isinstance(block, dict):
        raise InputError("muscle must be an object", source=source, field="muscle")
    unknown = set(block) - set(MUSCLE_DYNAMICS_KEYS)
    if unknown:
        raise InputError(f"unknown muscle entry {sorted(unknown)[0]!r} (expected "
                         f"{', '.join(MUSCLE_DYNAMICS_KEYS)})", source=source,
                         field="muscle." + sorted(unknown)[0])
    out = {}
    for key, v in block.items():
        if _file_number(v) is None:
            raise InputError(f"{key} must be a number (got {v!r})", source=source,
                             field="muscle." + key)
        name, scale = MUSCLE_DYNAMICS_KEYS[key]
        out[name] = _file_number(v) * scale
    values = {"fv_vmax": base.fv_vmax, "fv_curvature": base.fv_curvature,
              "tau_activation": base.tau_activation,
              "activation_damping": base.activation_damping, **out}
    try:
        check_muscle_dynamics(values["fv_vmax"], values["fv_curvature"],
                              values["tau_activation"], values["activation_damping"])
    except InputError as exc:
        key = next(k for k, (f, _) in MUSCLE_DYNAMICS_KEYS.items() if f == exc.field)
        raise InputError(exc.message, source=source, field="muscle." + key) from None
    return out


def _read_jaw(jaw, base: Parameters, source: str) -> dict:
    """The jaw kinematics of a preset file's ``jaw`` block (absent: the base preset's)."""
    if jaw is None:
        return {}
    if not isinstance(jaw, dict):
        raise InputError("jaw must be an object", source=source, field="jaw")
    unknown = set(jaw) - {"kinematics", "glide_rate_mm_per_rad", "glide_slope_deg"}
    if unknown:
        raise InputError(f"unknown jaw entry {sorted(unknown)[0]!r}", source=source,
                         field="jaw." + sorted(unknown)[0])
    kin = jaw.get("kinematics", base.jaw_kinematics)
    out = {"jaw_kinematics": kin, "glide_rate": base.glide_rate,
           "glide_slope": base.glide_slope}
    for key, field_name, scale in (("glide_rate_mm_per_rad", "glide_rate", 1e-3),
                                   ("glide_slope_deg", "glide_slope", np.pi / 180)):
        if key in jaw:
            v = jaw[key]
            if _file_number(v) is None:
                raise InputError(f"{key} must be a number (got {v!r})", source=source,
                                 field="jaw." + key)
            out[field_name] = _file_number(v) * scale
    try:
        check_jaw_kinematics(out["jaw_kinematics"], out["glide_rate"], out["glide_slope"])
    except InputError as exc:
        key = {"jaw_kinematics": "kinematics", "glide_rate": "glide_rate_mm_per_rad",
               "glide_slope": "glide_slope_deg"}[exc.field]
        raise InputError(exc.message, source=source, field="jaw." + key) from None
    return out


def write_preset(path, name: str, scales: dict, extra: dict | None = None, *,
                 jaw_kinematics: str = "glide", glide_rate: float = GLIDE_RATE,
                 glide_slope: float = GLIDE_SLOPE) -> None:
    """Save a calibrated anatomical preset (JSON, written atomically).

    The file holds the base preset, its ``scales`` and a ``jaw`` block: the kinematics
    (``"glide"``, the anatomical preset's, or ``"hinge"``), the glide's rate (mm/rad) and slope
    (degrees below the horizontal); all are checked before anything is written.
    """
    import json

    from .atomic import atomic_path

    check_jaw_kinematics(jaw_kinematics, glide_rate, glide_slope)
    data = {"format": "facemech-preset", "version": 1, "name": name, "base": "anatomical",
            "scales": {k: float(v) for k, v in scales.items()},
            "jaw": {"kinematics": jaw_kinematics,
                    "glide_rate_mm_per_rad": float(glide_rate) * 1e3,
                    "glide_slope_deg": float(np.degrees(glide_slope))},
            **(extra or {})}
    with atomic_path(path, suffix=".json") as tmp:
        tmp.write_text(json.dumps(data, indent=2))


PRESETS = ("anatomical", "lucero1999", "pitermann2001", "calibrated")
DEFAULT_PRESET = "anatomical"


class Preset(NamedTuple):
    """A preset as a command takes it: its :class:`Parameters` and its
    :class:`~facemech.stepping.StepOptions` (:func:`preset_pair`)."""

    params: Parameters
    steps: StepOptions

    def with_(self, **changes) -> Preset:
        """A copy with some fields of either changed (each checked where it lives)."""
        method, physical = split_overrides(changes)
        return Preset(self.params.with_(**physical) if physical else self.params,
                      self.steps.with_(**method) if method else self.steps)


def preset_pair(name: str) -> Preset:
    """The :class:`Preset` of a name or a ``.json`` file: :func:`preset`, :func:`preset_steps`."""
    return Preset(preset(name), preset_steps(name))


def preset_steps(name: str) -> StepOptions:
    """The numerical method of a preset (name or ``.json`` file; :func:`preset`'s names):
    :data:`facemech.stepping.PRESET_STEPS`, a file's with its ``step`` block."""
    name = str(name)
    if name in PRESET_STEPS:
        return PRESET_STEPS[name]
    if name.lower().endswith(".json"):
        return read_preset_steps(name)
    preset(name)  # the unknown name's error
    raise AssertionError(name)


def default_parameters() -> Parameters:
    """The parameters every command and function uses when none are given: the default preset."""
    return preset(DEFAULT_PRESET)
