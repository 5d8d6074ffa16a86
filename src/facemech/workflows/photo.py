"""A talker from photos: ``facemech face from-photo FRONT.jpg [--profile SIDE.jpg] -o talker.npz``.

The photo's face is found and its 68 iBUG landmarks placed (:mod:`facemech.io.photo`, dlib),
the generic face fitted to them (:mod:`facemech.geometry.photo_fit`), the photo painted on it
(:mod:`facemech.viz.photo_texture`), and the result built like a scan
(:func:`facemech.geometry.builder.build_face`): a face that simulates, renders, speaks and
exports like any other.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..progress import StagedProgress
from .outcome import Written


@dataclass(frozen=True)
class PhotoFace:
    """What :func:`face_from_photo` made.

    Attributes
    ----------
    model : the :class:`~facemech.geometry.model.FaceModel`
    fit : the :class:`~facemech.geometry.photo_fit.PhotoFit` (surface, landmarks, camera)
    texture : the :class:`~facemech.viz.photo_texture.BakedTexture`
    points : (68, 2) the landmarks found in the frontal photo, px
    """

    model: object
    fit: object
    texture: object
    points: np.ndarray


def face_from_photo(front: np.ndarray, *, profile: np.ndarray | None = None,
                    points: np.ndarray | None = None, ipd: float | None = None,
                    distance: float = 1.0, name: str = "photo", tissue: str = "anatomical",
                    source: str = "front", profile_source: str = "profile",
                    detector=None, delight: bool = True, offsets="dlib") -> PhotoFace:
    """Build a textured face model from a frontal photo (and a profile).

    Parameters
    ----------
    front : (h, w, 3) uint8 sRGB, the frontal photo
    profile : (h, w, 3) uint8 sRGB, a profile photo against a plain background, or None
    points : (68, 2) iBUG landmarks of the frontal photo, px (x right, y down), to skip the
        detector; None finds them (dlib, the ``photo`` extra)
    ipd : the subject's interpupillary distance, m; None: the adult norm (63.4 mm, Dodgson
        2004)
    distance : m from the camera to the face
    name : the model's name
    tissue : ``anatomical`` or ``uniform``
    source, profile_source : the photos' names, for errors
    detector : a :class:`~facemech.io.photo.DlibDetector` to reuse (None: one is made)
    delight : divide the photo by the renderer's light (:mod:`~facemech.viz.photo_texture`)
    offsets : where the points' detector puts the iBUG points on the generic face:
        ``"dlib"`` (:data:`~facemech.geometry.photo_fit.DLIB_OFFSETS_MM`), None for points in
        facemech's own placement, or a (68, 2) array, mm

    Raises
    ------
    InputError
        A photo without exactly one frontal face of at least 40 px, a profile that is a
        frontal photo or shows no face outline, a scale or distance out of range.
    """
    from ..geometry.builder import build_face, tissue_options
    from ..geometry.photo_fit import DLIB_OFFSETS_MM, fit_frontal, profile_silhouette
    from ..io.photo import DlibDetector, check_profile, frontal_landmarks
    from ..viz.photo_texture import bake_photo_texture

    opts = tissue_options(tissue)
    if points is None:
        detector = detector or DlibDetector()
        points = frontal_landmarks(front, source=source, detector=detector).points
    silhouette = None
    if profile is not None:
        if detector is not None:
            check_profile(profile, source=profile_source, detector=detector)
        silhouette = profile_silhouette(profile, source=profile_source)
    if isinstance(offsets, str) and offsets == "dlib":
        offsets = DLIB_OFFSETS_MM
    fit = fit_frontal(points, front.shape[:2], ipd=ipd, distance=distance, profile=silhouette,
                      offsets=offsets, source=source)
    texture = bake_photo_texture(fit, front, delight=delight, source=source)
    notes: list[str] = []
    model = build_face(fit.vertices, fit.faces, fit.landmarks, name=name, source=source,
                       options=opts, appearance=texture.appearance, notes=notes)
    return PhotoFace(model, fit, texture, np.asarray(points, float))


def face_from_photo_file(front: str | Path, output: str | Path, *,
                         profile: str | Path | None = None, ipd: float | None = None,
                         distance: float = 1.0, name: str | None = None,
                         tissue: str = "anatomical",
                         progress: StagedProgress | None = None) -> Written:
    """Build a talker from a frontal photo (and a profile); save it to ``output`` (``.npz``).

    Parameters
    ----------
    front : the frontal photo (JPEG, PNG, ...)
    output : the model file (``.npz``), written atomically; never one of the photos
    profile : a profile photo against a plain background: its outline corrects the depth of
        the nose, lips and chin
    ipd : interpupillary distance, mm (None: the adult norm, 63.4 mm, Dodgson 2004)
    distance : camera to face, m (1.0 default: a portrait at arm's length and more)
    name : model name (default: the photo's stem)
    tissue : ``anatomical`` or ``uniform``
    progress : staged callback; stages ``detect``, ``fit``, ``build`` (0 then 1 each)

    Returns
    -------
    Written : ``data`` the :class:`PhotoFace`; its line gives the scale and where it came
        from, the share of the skin painted from the photo, and the model's counts
    """
    from ..atomic import check_output
    from ..checks import check_value
    from ..errors import InputError
    from ..io.photo import DlibDetector, check_profile, frontal_landmarks, read_photo

    front = Path(front)
    if not str(output).lower().endswith(".npz"):
        raise InputError("the talker is a .npz face file", source=str(output), field="-o")
    check_output(output, [front, profile], field="-o")
    if ipd is not None:
        check_value("ipd", ipd)  # mm, the command line's interval (facemech.checks)
    check_value("distance", distance)  # m

    def say(stage, done):
        if progress is not None:
            progress(stage, done, 1)

    say("detect", 0)
    image = read_photo(front)
    side = None if profile is None else read_photo(profile, field="--profile")
    detector = DlibDetector()
    found = frontal_landmarks(image, source=str(front), detector=detector)
    if side is not None:
        check_profile(side, source=str(profile), detector=detector)
    say("detect", 1)
    say("fit", 0)
    made = face_from_photo(image, profile=side, points=found.points,
                           ipd=None if ipd is None else ipd * 1e-3, distance=distance,
                           name=name or front.stem, tissue=tissue, source=str(front),
                           profile_source=str(profile) if profile else "profile")
    say("fit", 1)
    say("build", 0)
    made.model.save(output)
    say("build", 1)
    s = made.model.summary()
    seen = float(made.texture.coverage.mean())
    return Written(Path(output), made,
                   f"built {s['name']} from {front.name}"
                   f"{'' if profile is None else ' and ' + Path(profile).name}: "
                   f"{s['nodes_per_layer']['epidermis']} nodes per layer, {s['muscles']} "
                   f"muscles, {seen:.0%} of the texture from the photo -> {output}",
                   f"facemech: note: {made.fit.note()}; {made.texture.note}\n")
