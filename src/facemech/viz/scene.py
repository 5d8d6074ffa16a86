"""The rendered scene: the moving skin plus render-only anatomy that the physics does not carry.

* **skin**: the results' epidermis, coloured by the scan's texture or vertex colours, else a
  procedural texture from its landmarks, the palpebral fissures cut out (:mod:`.face_parts`);
* **eyes**: eyeballs behind the fissures turned by the gaze, lids that close with the blink
  (:mod:`.face_parts`, :mod:`.lids`; a textured face's from its own image, :mod:`.fissures`);
* **mouth**: a dark cavity, the upper teeth on the skull, the lower teeth and the tongue moving
  with the mandible (jaw angle about the hinge, plus its shift; the tongue tip bent by its pose,
  :mod:`.dentition`), and a dark seal across the slit between the lips;
* **nose and shape** (the built-in face): alae and nostrils carried by the skin (:mod:`.nose`,
  :mod:`.attach`); the drawn skin's cheekbones, mouth width and folds (:mod:`.shape`,
  :mod:`.folds`);
* **head motion**: every part turns rigidly about :func:`head_pivot` by a pose (pitch, yaw,
  roll) rad (:func:`head_rotation`); the skin's simulated positions stay in the head's frame;
* **head**: a closure from the skin's edge round the back of the head (:mod:`.closure`,
  :mod:`.cranium`) with hair (:mod:`.hair`) and ears (:mod:`.ears`), or a head shell with a
  skirt from the skin's edge (:mod:`.head`).

:func:`build_scene` packs the parts for the rasteriser (one vertex array, one texture atlas);
:meth:`Scene.frame` places them for one time step. What is drawn: docs/rendering.md.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field

import numpy as np

from ..geometry.builder import vertex_normals
from ..geometry.jaw import rotation_matrix
from .dentition import bend_tongue, tongue_modes
from .face_parts import MAX_TEXTURE, eye_parts, mouth_parts, skin_part, textured_fissures
from .head import SKIRT_DEPTH, closed_head, ear_parts, head_centre, head_shell, skirt_part
from .lids import gaze_rotation
from .look import FaceLook, look_from_dataset, look_from_model
from .mesh import Part, VertexNormals
from .nose import nose_parts
from .raster import srgb_to_linear
from .shape import drawn_shape

__all__ = ["FaceLook", "MAX_TEXTURE", "Part", "SKIRT_DEPTH", "Scene", "build_scene",
           "head_pivot", "head_rotation", "look_from_dataset", "look_from_model"]

_REST_LOCK = threading.Lock()  #: guards the one-time build of a scene's rest arrays


@dataclass(frozen=True)
class Scene:
    """All parts packed for the rasteriser; :meth:`frame` places them for one time step."""

    parts: tuple[Part, ...]
    look: FaceLook
    tris: np.ndarray  # (F, 3) int32
    uv: np.ndarray  # (F, 3, 2) float32 atlas texels
    tex: np.ndarray  # (F,) int8
    alpha_test: np.ndarray  # (F,) bool
    two_sided: np.ndarray  # (F,) bool
    atlas: np.ndarray  # (H, W, 4) float32 linear
    albedo: np.ndarray  # (N, 3) float32 linear
    gloss: np.ndarray  # (N, 2) float32
    offsets: np.ndarray  # (parts + 1,) vertex offsets
    rest_normals: tuple = ()  # per part, (n, 3) unit normals at rest
    centre: np.ndarray = field(default_factory=lambda: np.zeros(3))  # of the head, m
    joint_faces: np.ndarray | None = None  # skin + closure faces over [skin, closure] vertices
    joint_normals: VertexNormals | None = None  # of the joint mesh
    framing: dict = field(default_factory=dict)
    tongue_modes: np.ndarray | None = None  # (n, 2, 3) of the 'tongue' part (.dentition)
    shape: object | None = None  # the drawn skin's shape (:class:`.shape.DrawnShape`)

    def frame(self, skin: np.ndarray, jaw_angle=0.0, blink: float = 0.0,
              gaze=(0.0, 0.0), head=None, tongue=None) -> tuple[np.ndarray, np.ndarray]:
        """Vertices (N, 3) and unit normals (N, 3) of every part for one frame (model axes).

        ``jaw_angle``: the jaw's angle (rad), or its pose (3,) (angle rad, shift_y m, shift_z
        m): the mandible's parts turn about the hinge and move with its shift. ``blink``: the
        lids' closure, 0 open .. 1 closed; ``gaze``: (yaw, pitch) rad of both eyes,
        yaw > 0 towards the subject's left, pitch > 0 up (:mod:`.lids`); ``head``: None, or the
        head's pose (3,) rad (pitch up, yaw to the subject's left, roll to the left): every
        part turns about :func:`head_pivot` (:func:`head_rotation`); ``tongue``: None, or the
        tongue tip's pose (2,) m (protrusion, elevation) in the mandible's frame
        (:func:`.dentition.bend_tongue`; :mod:`facemech.speech.tongue`).

        Safe to call from several threads at once (a movie's frame pool,
        :mod:`.frame_pool`): the scene's packed arrays are only read; each call starts from
        its own copy of the rest vertices and normals (N, 3) and overwrites the moving parts
        there, so no call sees another's.
        """
        look = self.look
        yaw, pitch = (float(g) for g in gaze)
        turned = yaw != 0.0 or pitch != 0.0
        eye_rot = gaze_rotation(yaw, pitch) if turned else None
        angle, shift = jaw_pose_of(jaw_angle)
        moved = angle != 0.0 or shift[1] != 0.0 or shift[2] != 0.0
        rot = rotation_matrix(look.hinge_axis, angle)
        skin = np.asarray(skin, float)
        if self.shape is not None:  # drawn, not simulated: cheekbones, folds (.shape)
            skin = self.shape.apply(skin)
        rest_v, rest_n, normals = self._rest()
        verts, norms = rest_v.copy(), rest_n.copy()  # the parts that keep still stay so
        skin_normals = None
        closure = next((p for p in self.parts if p.motion == "follow"), None)
        if closure is not None:
            # skin and head are one surface: their normals are the joint mesh's
            cv = closure.follow.place(skin, look.rest)
            joint = self.joint_normals(np.concatenate([skin, cv]))
            n_skin = len(skin)
            e = len(closure.follow.loop)
            skin_normals = joint[:n_skin]
            closure_normals = joint[n_skin:]
            closure_normals[:e] = skin_normals[closure.follow.loop]
        for k, (p, n_rest) in enumerate(zip(self.parts, self.rest_normals, strict=True)):
            if p.motion == "skin":
                v = skin
                if skin_normals is None:  # the skin's own (the first part); others share nodes
                    skin_normals = normals[k](v)
                n = skin_normals
            elif p.motion == "follow":
                v, n = cv, closure_normals
            elif p.motion == "attached":  # render-only shapes carried by the skin (.attach)
                v = p.follow.place(skin, skin_normals)
                n = p.follow.shade_normals(normals[k](v), skin_normals)
            elif p.motion == "eye":
                if not turned:
                    continue
                v = (p.rest - p.pivot) @ eye_rot.T + p.pivot
                n = n_rest @ eye_rot.T
            elif p.motion == "lid":
                if p.follow.at_rest(blink, pitch):
                    continue
                v = p.follow.place(blink, pitch)
                n = normals[k](v)
            elif p.motion == "skirt":  # from the skin's edge nodes in towards the head's centre
                nodes = p.skirt_nodes
                edge = skin[nodes]
                inward = self.centre - edge
                inward /= np.linalg.norm(inward, axis=1, keepdims=True)
                v = np.concatenate([edge, edge + SKIRT_DEPTH * inward])
                n = np.concatenate([skin_normals[nodes]] * 2)
            else:
                bent = p.name == "tongue" and tongue is not None and np.any(np.asarray(tongue))
                if not bent and not (p.motion == "jaw" and moved):
                    continue
                v = p.rest
                n = n_rest
                if bent:
                    v = bend_tongue(p.rest, self.tongue_modes, tongue)
                    n = normals[k](v)
                if p.motion == "jaw" and moved:
                    v = (v - look.hinge_point) @ rot.T + look.hinge_point + shift
                    n = n @ rot.T
            a, b = self.offsets[k], self.offsets[k + 1]
            verts[a:b] = v
            if p.inward:
                np.negative(n, out=norms[a:b])
            else:
                norms[a:b] = n
        if head is not None and np.any(np.asarray(head, float) != 0.0):
            r = head_rotation(head)
            pivot = head_pivot(self)
            verts = (verts - pivot) @ r.T + pivot
            norms = norms @ r.T
        return verts, norms


    def _rest(self) -> tuple[np.ndarray, np.ndarray, list]:
        """Every part's vertices (N, 3) and unit normals (N, 3, inward parts' turned) at rest,
        and per part a :class:`.mesh.VertexNormals` of its faces (built once per scene)."""
        cached = self.__dict__.get("_rest_cache")
        if cached is not None:
            return cached
        with _REST_LOCK:  # built once, also when a movie's threads ask for it together
            cached = self.__dict__.get("_rest_cache")
            if cached is not None:
                return cached
            verts = np.concatenate([np.asarray(p.rest, float) for p in self.parts])
            norms = np.concatenate([-n if p.inward else n
                                    for p, n in zip(self.parts, self.rest_normals, strict=True)])
            normals = [VertexNormals(p.faces, len(p.rest)) for p in self.parts]
            cached = (verts, norms.astype(float), normals)
            object.__setattr__(self, "_rest_cache", cached)  # a cache on a frozen scene
            return cached

#: m, the head's pivot (the top of the neck, about the occipital condyles) below the centre of
#: the head's sphere (:func:`.head.head_centre`), our estimate
PIVOT_BELOW_CENTRE = 0.085


def head_pivot(scene: Scene) -> np.ndarray:
    """(3,) m, the point the head turns about: on the midline, at the depth of the head's
    centre, :data:`PIVOT_BELOW_CENTRE` below it (model axes)."""
    c = np.asarray(scene.centre, float)
    return np.array([0.0, c[1] - PIVOT_BELOW_CENTRE, c[2]])


def head_rotation(pose) -> np.ndarray:
    """(3, 3) rotation of a head pose (pitch, yaw, roll) rad: pitch > 0 raises the face,
    yaw > 0 turns it to the subject's left (+x), roll > 0 tilts the top to the left;
    ``R = R_yaw @ R_pitch @ R_roll``."""
    pitch, yaw, roll = (float(v) for v in np.asarray(pose, float).reshape(3))
    cr, sr = np.cos(roll), np.sin(roll)
    rz = np.array([[cr, sr, 0.0], [-sr, cr, 0.0], [0.0, 0.0, 1.0]])
    return gaze_rotation(yaw, pitch) @ rz


def jaw_pose_of(jaw) -> tuple[float, np.ndarray]:
    """(angle rad, shift (3,) m) of a jaw angle or a (3,) pose (angle, shift_y, shift_z)."""
    pose = np.asarray(jaw, float)
    if pose.ndim == 0:
        return float(pose), np.zeros(3)
    if pose.shape != (3,):
        raise ValueError(f"a jaw angle or a (3,) pose, not an array of shape {pose.shape}")
    return float(pose[0]), np.array([0.0, pose[1], pose[2]])


def build_scene(look: FaceLook, *, eyes: bool = True, mouth: bool = True,
                head: bool = True) -> Scene:
    """Assemble and pack the parts of a face's scene."""
    closed = closed_head(look) if head else None
    # a textured face's fissures are cut from its image where its eyes are drawn
    fissures = textured_fissures(look) if eyes else None
    parts = [skin_part(look, painted_hair=closed is None, fissures=fissures)]
    if head and not look.textured:  # the built-in face: the nose's base (.nose)
        parts += nose_parts(look, parts[0])
    if eyes and (not look.textured or fissures is not None):
        parts += eye_parts(look, fissures)
    if mouth:
        parts += mouth_parts(look)
    if head:
        if closed is not None:
            parts += closed
        elif (shell := head_shell(look)) is not None:
            parts.append(shell)
            skirt = skirt_part(look)
            if skirt is not None:
                parts.append(skirt)
            parts += ear_parts(look)
    scene = _pack(parts, look)
    if head:
        object.__setattr__(scene, "shape", drawn_shape(look))
    return scene


def _pack(parts: list[Part], look: FaceLook) -> Scene:
    textures = [p.texture for p in parts if p.texture is not None]
    width = max([t.shape[1] for t in textures] + [1])
    rows, offsets_tex, y = [], {}, 0
    for p in parts:
        if p.texture is not None:
            t = p.texture
            pad = np.zeros((t.shape[0], width, 4))
            pad[:, : t.shape[1]] = t
            pad[:, t.shape[1]:] = t[:, -1:]
            offsets_tex[p.name] = y
            rows.append(pad)
            rows.append(pad[-1:].repeat(2, axis=0))  # a guard band against bleeding
            y += t.shape[0] + 2
    atlas = np.concatenate(rows) if rows else np.ones((1, 1, 4))
    atlas = atlas.astype(np.float32)
    atlas[..., :3] = srgb_to_linear(atlas[..., :3])
    tris, uv, tex, alpha, albedo, gloss, offs = [], [], [], [], [], [], [0]
    two = []
    for p in parts:
        base = offs[-1]
        f = np.asarray(p.faces, np.int64) + base
        tris.append(f)
        if p.uv is not None:
            q = np.array(p.uv, np.float32)
            q[..., 1] += offsets_tex[p.name]
            mask = np.ones(len(f), bool) if p.tex_mask is None else p.tex_mask
            tex.append(mask.astype(np.int8))
        else:
            q = np.zeros((len(f), 3, 2), np.float32)
            tex.append(np.zeros(len(f), np.int8))
        uv.append(q)
        cut = (tex[-1] > 0) & p.alpha_test
        if cut.any():  # test alpha only where the triangle's texels hold a cut-out
            cut &= _touches_cutout(q, atlas)
        alpha.append(cut)
        two.append(np.zeros(len(f), bool) if p.two_sided is None else p.two_sided)
        albedo.append(srgb_to_linear(np.clip(p.albedo, 0, 1)))
        g = np.asarray(p.gloss, np.float32)
        gloss.append(g if g.ndim == 2 else np.tile(g, (len(p.rest), 1)))
        offs.append(base + len(p.rest))
    scene = Scene(tuple(parts), look, np.concatenate(tris).astype(np.int32),
                  np.concatenate(uv).astype(np.float32), np.concatenate(tex),
                  np.concatenate(alpha), np.concatenate(two), atlas,
                  np.concatenate(albedo).astype(np.float32),
                  np.concatenate(gloss).astype(np.float32), np.array(offs),
                  tuple(vertex_normals(p.rest, p.faces) for p in parts),
                  head_centre(look)[0])
    object.__setattr__(scene, "framing", _framing(scene))
    tongue = next((p for p in parts if p.name == "tongue"), None)
    if tongue is not None:
        object.__setattr__(scene, "tongue_modes", tongue_modes(tongue.rest))
    closure = next((p.follow for p in parts if p.motion == "follow"), None)
    if closure is not None:
        skin = parts[0]
        joint = np.concatenate([skin.faces, closure.joint_faces(len(skin.rest))])
        object.__setattr__(scene, "joint_faces", joint)
        object.__setattr__(scene, "joint_normals",
                           VertexNormals(joint, len(skin.rest) + len(closure.rest)))
    return scene


def _touches_cutout(uv: np.ndarray, atlas: np.ndarray) -> np.ndarray:
    """(f,) bool: whether a texel of alpha < 0.5 lies in each triangle's texel bounding box."""
    holes = (atlas[..., 3] < 0.5).astype(np.int64)
    sat = np.zeros((holes.shape[0] + 1, holes.shape[1] + 1), np.int64)
    sat[1:, 1:] = holes.cumsum(0).cumsum(1)
    h, w = holes.shape
    u0 = np.clip(np.floor(uv[..., 0].min(axis=1)).astype(int) - 1, 0, w)
    u1 = np.clip(np.ceil(uv[..., 0].max(axis=1)).astype(int) + 1, 0, w)
    v0 = np.clip(np.floor(uv[..., 1].min(axis=1)).astype(int) - 1, 0, h)
    v1 = np.clip(np.ceil(uv[..., 1].max(axis=1)).astype(int) + 1, 0, h)
    return (sat[v1, u1] - sat[v0, u1] - sat[v1, u0] + sat[v0, u0]) > 0


def _framing(scene: Scene) -> dict:
    """What the views frame: the head from its top to 35 mm under the menton, and the mouth."""
    look = scene.look
    outer = [p.rest for p in scene.parts if p.name in ("skin", "head", "hair")]
    allv = np.concatenate(outer or [p.rest for p in scene.parts])  # or a scene of inner parts
    top = allv[:, 1].max()
    lm = look.landmarks
    bottom = (lm["menton"][1] if "menton" in lm else look.rest[:, 1].min()) - 0.035
    st = lm.get("stomion", lm.get("upper_lip_center", np.median(look.rest, axis=0)))
    return {"points": allv[(allv[:, 1] >= bottom) & (allv[:, 1] <= top)],
            "mouth": np.asarray(st, float), "mouth_half_height": 0.032}
