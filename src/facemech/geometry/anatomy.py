"""Muscle attachments and virtual marker sites, placed on the generic face.

Each site is a frontal ``(x, y)`` position in mm on the generic face of :mod:`generic` (right side,
``x < 0``; the left-side twin mirrors ``x``).  For any other face the sites are carried over by the
thin-plate-spline warp that takes the generic landmarks onto that face's landmarks, then snapped
to the nearest node (see :mod:`sites` and :mod:`muscle_sites`).  Origins and insertions follow
ANATOMY.md (Kennedy & Abbs 1979 via the seeds): origins on bone are skull-layer nodes, those on
the mandible belong to the jaw; insertions are fascia-layer nodes.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class LinearMuscleSite:
    """A straight muscle: origin (bone) and insertion (skin), frontal (x, y) mm, right side."""

    group: str
    origin: tuple[float, float]
    insertion: tuple[float, float]
    on_mandible: bool = False
    description: str = ""
    name: str = ""  # instance name stem (default: the group)
    #: anatomical tissue: the origin is in the soft tissue at the depth of the muscle plane
    #: (a fascia that does not move), not on bone: risorius arises from the parotid and
    #: masseteric fascia and runs along the cheek under the skin
    origin_in_fascia: bool = False


# Right-side sites; the left twin mirrors x.  (x, y) in mm on the generic face, origin at nasion.
LINEAR_MUSCLES: tuple[LinearMuscleSite, ...] = (
    LinearMuscleSite("ZYG", (-56.0, -32.0), (-32.0, -71.0), False,
                     "zygomatic major: zygomatic bone -> modiolus"),
    LinearMuscleSite("ZMI", (-44.0, -28.0), (-15.0, -63.0), False,
                     "zygomatic minor: malar surface -> lateral upper lip"),
    LinearMuscleSite("LAO", (-22.0, -42.0), (-30.0, -69.0), False,
                     "levator anguli oris: canine fossa -> modiolus"),
    LinearMuscleSite("LLS", (-26.0, -20.0), (-10.0, -62.0), False,
                     "levator labii superioris: infraorbital margin -> upper lip"),
    LinearMuscleSite("LLSAN", (-13.0, -6.0), (-7.0, -59.0), False,
                     "levator labii superioris alaeque nasi: frontal process -> ala, upper lip"),
    LinearMuscleSite("RIS", (-56.0, -80.0), (-32.0, -75.0), False,
                     "risorius: masseteric fascia -> modiolus", origin_in_fascia=True),
    LinearMuscleSite("DAO", (-30.0, -113.0), (-31.0, -78.0), True,
                     "depressor anguli oris: oblique line of the mandible -> modiolus"),
    LinearMuscleSite("DLI", (-15.0, -108.0), (-9.0, -84.0), True,
                     "depressor labii inferioris: mandible -> lower lip"),
    LinearMuscleSite("MEN", (-5.0, -96.0), (-7.0, -111.0), True,
                     "mentalis: incisive fossa -> skin of the chin"),
    LinearMuscleSite("FRM", (-25.0, 76.0), (-25.0, 16.0), False,
                     "frontalis, central belly: galea -> brow"),
    LinearMuscleSite("FRL", (-44.0, 72.0), (-42.0, 13.0), False,
                     "frontalis, lateral part: galea -> lateral brow"),
    LinearMuscleSite("FRI", (-9.0, 76.0), (-10.0, 15.0), False,
                     "frontalis, inner part: galea -> medial brow"),
    LinearMuscleSite("COR", (-10.0, 7.0), (-27.0, 15.0), False,
                     "corrugator: medial superciliary arch -> mid brow skin"),
    LinearMuscleSite("CSU", (-13.0, 4.0), (-21.0, 19.0), False,
                     "corrugator supercilii, superficial slip -> brow skin"),
)

#: The incisive bundles of orbicularis oris (incisivus labii superioris and inferioris), built
#: only in the anatomical tissue: accessory slips of the muscle that arise from the alveolar bone
#: over the lateral incisors, deep to the lip, and run laterally to the modiolus. They are
#: driven with their part of the sphincter (OOS, OOI) and draw the mouth corners medially and
#: forward along the dental arch, which, with the lips' volume on the teeth, protrudes the lips.
INCISIVE_MUSCLES: tuple[LinearMuscleSite, ...] = (
    LinearMuscleSite("OOS", (-10.0, -55.0), (-29.0, -71.0), False,
                     "incisivus labii superioris: maxillary alveolus -> modiolus",
                     name="OOS_incisive"),
    LinearMuscleSite("OOI", (-10.0, -91.0), (-29.0, -75.0), True,
                     "incisivus labii inferioris: mandibular alveolus -> modiolus",
                     name="OOI_incisive"),
)

#: Sphincter groups: orbicularis oris superior and inferior, in that order (upper lip, lower
#: lip); each side a half path from the mouth corner to the midline along the lip margin
#: (:func:`facemech.geometry.muscle_sites.sphincter_paths`).
SPHINCTERS: tuple[str, ...] = ("OOS", "OOI")

#: The marginal part (pars marginalis) of orbicularis oris, upper and lower lip, built only in
#: the anatomical tissue: fibres along the red lip close to its free margin (ANATOMY.md; Rogers
#: et al. 2009). Each side runs from the modiolus to the midline through the vermilion, arched
#: away from the lip line as the red lip widens toward the midline, so that its tension lowers
#: the upper lip and lifts the lower lip toward the line, presses them onto the teeth and
#: together, and turns the vermilion in (:func:`facemech.geometry.muscle_sites.sphincter_paths`).
MARGINAL: tuple[str, ...] = ("OOSM", "OOIM")

# Virtual OPTOTRAK-like markers: 11 on the right half of the lower face (R01 on the chin, used to
# drive the jaw), 8 on the left half for held-out checks.  (x, y) mm on the generic face.
RIGHT_MARKERS: dict[str, tuple[float, float]] = {
    "R01": (-4.0, -110.0),   # chin, near the midline (drives the jaw)
    "R02": (-22.0, -104.0),  # chin, lateral
    "R03": (-7.0, -82.0),    # lower lip, paramedian
    "R04": (-16.0, -79.0),   # lower lip, lateral
    "R05": (-7.0, -64.0),    # upper lip, paramedian
    "R06": (-16.0, -66.0),   # upper lip, lateral
    "R07": (-26.0, -73.0),   # mouth corner
    "R08": (-32.0, -90.0),   # cheek below the corner
    "R09": (-40.0, -72.0),   # cheek lateral to the corner
    "R10": (-38.0, -52.0),   # upper cheek
    "R11": (-23.0, -57.0),   # nasolabial region
}
LEFT_MARKERS: dict[str, tuple[float, float]] = {
    "L01": (4.0, -110.0),
    "L02": (7.0, -82.0),
    "L03": (16.0, -79.0),
    "L04": (7.0, -64.0),
    "L05": (16.0, -66.0),
    "L06": (26.0, -73.0),
    "L07": (40.0, -72.0),
    "L08": (32.0, -90.0),
}
