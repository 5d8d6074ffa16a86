"""How a scanned face looks: its texture (per-corner UVs and an image) or its vertex colours.

A textured scan (OBJ + MTL + image, or a PLY with colours) keeps its look through the model
builder, the ``.npz`` face file and the results NetCDF, so that a renderer can paint the scan's
own skin on the moving surface.

Texture coordinates are stored per triangle corner, ``uv[t, k]`` for corner ``k`` of triangle
``t`` of the epidermal surface (``FaceModel.faces[t, k]``, the results' ``triangles``): a
textured scan has UV seams, where one point of the skin has two texture coordinates, while the
geometry stays one node per position (the physics needs a surface without cracks). The
convention is OpenGL's: ``u`` runs right and ``v`` up, ``(0, 0)`` is the bottom-left corner of
the image and ``(1, 1)`` its top-right corner; the image is stored as read, row 0 at the top.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError

#: tolerance on texture coordinates outside [0, 1] (rounding in exporters)
UV_TOLERANCE = 1e-3


@dataclass(frozen=True, eq=False)
class Appearance:
    """The look of a face surface.

    Parameters
    ----------
    uv : (f, 3, 2) float32 array or None
        Texture coordinates of every triangle corner, in [0, 1] (OpenGL convention, see the
        module's docstring). Given together with ``image``.
    image : (h, w, 3) uint8 array or None
        RGB texture image, row 0 at the top (alpha dropped).
    vertex_colours : (n, 3) uint8 array or None
        RGB colour of every surface vertex (epidermal node).
    source : str
        The file the appearance came from.
    hair : (3,) uint8 array or None
        The hair's colour (sRGB) measured on a photo; None: the renderer's own.

    Raises
    ------
    InputError
        Bad shapes, non-finite or out-of-range texture coordinates, ``uv`` without ``image`` or
        the other way round, or nothing at all.
    """

    uv: np.ndarray | None = None
    image: np.ndarray | None = None
    vertex_colours: np.ndarray | None = None
    source: str = ""
    hair: np.ndarray | None = None

    def __post_init__(self) -> None:
        src = self.source or None
        if (self.uv is None) != (self.image is None):
            raise InputError("texture coordinates and a texture image go together",
                             source=src, field="uv" if self.uv is None else "image")
        if self.uv is None and self.vertex_colours is None:
            raise InputError("an appearance needs a texture or vertex colours", source=src,
                             field="appearance")
        if self.uv is not None:
            uv = np.asarray(self.uv)
            if uv.ndim != 3 or uv.shape[1:] != (3, 2) or len(uv) == 0:
                raise InputError(f"texture coordinates must be (triangles, 3, 2), got "
                                 f"{uv.shape}", source=src, field="uv")
            if not np.issubdtype(uv.dtype, np.number) or not np.all(np.isfinite(uv)):
                raise InputError("non-finite texture coordinates", source=src, field="uv")
            lo, hi = float(uv.min()), float(uv.max())
            if lo < -UV_TOLERANCE or hi > 1.0 + UV_TOLERANCE:
                raise InputError(f"texture coordinates outside [0, 1] ({lo:.3g} to {hi:.3g}); "
                                 "repeating (tiled) textures are not supported", source=src,
                                 field="uv")
            object.__setattr__(self, "uv", np.clip(uv, 0.0, 1.0).astype(np.float32))
            image = np.asarray(self.image)
            if image.ndim == 3 and image.shape[2] == 4:
                image = image[:, :, :3]
            if (image.ndim != 3 or image.shape[2] != 3 or image.shape[0] < 1
                    or image.shape[1] < 1):
                raise InputError(f"texture image must be (height, width, 3) RGB, got "
                                 f"{image.shape}", source=src, field="image")
            object.__setattr__(self, "image", _as_uint8(image, src, "image"))
        if self.vertex_colours is not None:
            vc = np.asarray(self.vertex_colours)
            if vc.ndim == 2 and vc.shape[1] == 4:
                vc = vc[:, :3]
            if vc.ndim != 2 or vc.shape[1] != 3 or len(vc) == 0:
                raise InputError(f"vertex colours must be (vertices, 3) RGB, got {vc.shape}",
                                 source=src, field="vertex_colours")
            object.__setattr__(self, "vertex_colours", _as_uint8(vc, src, "vertex_colours"))
        if self.hair is not None:
            hair = np.asarray(self.hair).reshape(-1)
            if hair.shape != (3,):
                raise InputError(f"the hair colour must be (3,) RGB, got {hair.shape}",
                                 source=src, field="hair")
            object.__setattr__(self, "hair", _as_uint8(hair, src, "hair"))
        object.__setattr__(self, "source", str(self.source))

    # ---- views ---------------------------------------------------------------------------
    @property
    def textured(self) -> bool:
        return self.uv is not None

    def describe(self) -> str:
        """One phrase: ``texture 1024x768``, ``vertex colours``, or both."""
        parts = []
        if self.image is not None:
            parts.append(f"texture {self.image.shape[1]}x{self.image.shape[0]}")
        if self.vertex_colours is not None:
            parts.append("vertex colours")
        return " and ".join(parts)

    def sample(self, uv: np.ndarray) -> np.ndarray:
        """Texture colour (nearest texel) at texture coordinates ``uv``.

        Parameters
        ----------
        uv : (..., 2) array, OpenGL convention

        Returns
        -------
        (..., 3) uint8 RGB
        """
        if self.image is None:
            raise InputError("the appearance has no texture", source=self.source or None,
                             field="image")
        h, w = self.image.shape[:2]
        uv = np.asarray(uv, float)
        col = np.clip(np.floor(uv[..., 0] * w), 0, w - 1).astype(np.int64)
        row = np.clip(np.floor((1.0 - uv[..., 1]) * h), 0, h - 1).astype(np.int64)
        return self.image[row, col]

    def check_surface(self, n_vertices: int, n_triangles: int, *,
                      source: str | None = None) -> None:
        """Raise unless the appearance fits a surface of these sizes."""
        if self.uv is not None and len(self.uv) != n_triangles:
            raise InputError(f"texture coordinates for {len(self.uv)} triangles, the surface "
                             f"has {n_triangles}", source=source, field="uv")
        if self.vertex_colours is not None and len(self.vertex_colours) != n_vertices:
            raise InputError(f"colours for {len(self.vertex_colours)} vertices, the surface has "
                             f"{n_vertices}", source=source, field="vertex_colours")

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Appearance):
            return NotImplemented
        return all(_same(getattr(self, k), getattr(other, k))
                   for k in ("uv", "image", "vertex_colours", "hair")) and (
            self.source == other.source)

    __hash__ = None  # type: ignore[assignment]


def _same(a, b) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return a.dtype == b.dtype and np.array_equal(a, b)


def _as_uint8(a: np.ndarray, source, field: str) -> np.ndarray:
    if a.dtype == np.uint8:
        return np.ascontiguousarray(a)
    if np.issubdtype(a.dtype, np.integer) and a.size and (a.min() < 0 or a.max() > 255):
        raise InputError("colours outside 0-255", source=source, field=field)
    if np.issubdtype(a.dtype, np.floating):
        if not np.all(np.isfinite(a)) or a.min() < 0 or a.max() > 255:
            raise InputError("colours non-finite or outside 0-255", source=source, field=field)
    if not np.issubdtype(a.dtype, np.number):
        raise InputError("colours are not numbers", source=source, field=field)
    return np.ascontiguousarray(np.round(a).astype(np.uint8))


# ---- results files ---------------------------------------------------------------------------
def dataset_variables(appearance: Appearance | None) -> tuple[dict, dict, dict]:
    """Variables, coordinates and attributes of an appearance in a results dataset.

    ``texture_uv`` (triangle, corner, uv) float32, ``texture_image`` (texel_y, texel_x, rgb)
    uint8 (row 0 at the top), ``vertex_colour`` (node, rgb) uint8; empty without one.
    """
    if appearance is None:
        return {}, {}, {}
    variables: dict = {}
    coords: dict = {"rgb": ["r", "g", "b"]}
    if appearance.uv is not None:
        coords["uv"] = ["u", "v"]
        variables["texture_uv"] = (
            ("triangle", "corner", "uv"), appearance.uv,
            {"long_name": "texture coordinates of each triangle corner",
             "convention": "OpenGL: u right, v up, (0, 0) the bottom-left corner of "
                           "texture_image, (1, 1) its top-right corner"})
        variables["texture_image"] = (
            ("texel_y", "texel_x", "rgb"), appearance.image,
            {"long_name": "RGB texture of the skin", "rows": "row 0 is the top of the image"})
    if appearance.vertex_colours is not None:
        variables["vertex_colour"] = (("node", "rgb"), appearance.vertex_colours,
                                      {"long_name": "RGB colour of each epidermal node"})
    if appearance.hair is not None:
        variables["hair_colour"] = (("rgb",), appearance.hair,
                                    {"long_name": "sRGB colour of the hair"})
    return variables, coords, {"appearance_source": appearance.source}


def appearance_from_dataset(ds) -> Appearance | None:
    """The appearance kept in a results dataset (:func:`facemech.io.results.read_results`).

    Returns ``None`` for results without one. ``uv[t, k]`` belongs to node
    ``ds.triangles[t, k]``.
    """
    uv = ds["texture_uv"].values if "texture_uv" in ds else None
    image = ds["texture_image"].values if "texture_image" in ds else None
    colours = ds["vertex_colour"].values if "vertex_colour" in ds else None
    hair = ds["hair_colour"].values if "hair_colour" in ds else None
    if uv is None and image is None and colours is None:
        return None
    return Appearance(uv=uv, image=image, vertex_colours=colours,
                      source=str(ds.attrs.get("appearance_source", "")), hair=hair)
