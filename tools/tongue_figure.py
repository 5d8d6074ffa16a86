"""Draw docs/img/tongue.jpg: the rendered tongue at the middle of a /θ/ ("_ T i: _") and of a
/t/ ("_ t a _") on the built-in face: the mouth from the front and from three-quarters, and the
tongue with the far half of the teeth alone in profile (the skin, cavity, gums and the near
teeth left out), the rest tongue dotted in grey for comparison (docs/rendering.md, docs/stimuli.md).

``python tools/tongue_figure.py [-o docs/img/tongue.jpg]`` (a minute or two).
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

import numpy as np

from facemech.physics.model import model as face_model

#: (label, eSpeak phones, their boundaries s, the time shown s)
CASES = (("/θ/ in _ T i: _", ("_", "T", "i:", "_"), (0.0, 0.3, 0.42, 0.7, 1.0), 0.36),
         ("/t/ in _ t a _", ("_", "t", "a", "_"), (0.0, 0.3, 0.38, 0.7, 1.0), 0.34))
SIZE = 320  #: pixels of each square panel


def _panels(face, labels, edges, when):
    """Three panels (h, w, 3) uint8 of one case, and its tongue pose (2,) m."""
    from facemech.solvers.forward import simulate
    from facemech.speech.alignment import Alignment, Segment
    from facemech.speech.coarticulation import controls_from_alignment
    from facemech.speech.tongue import tongue_tip
    from facemech.viz.camera import Camera, view_rotation
    from facemech.viz.render import parse_background, render_panel
    from facemech.viz.scene import _pack, build_scene, look_from_model

    phones = tuple(Segment(lab, a, b) for lab, a, b in zip(labels, edges[:-1], edges[1:],
                                                           strict=True))
    al = Alignment((), phones, "espeak", edges[-1])
    _, act, jaw = controls_from_alignment(al, frame_rate=60.0)
    sim = simulate(face_model(face), act, jaw)
    k = int(np.argmin(np.abs(sim.time - when)))
    pose = tongue_tip(al, sim.time)[k]
    look = look_from_model(face)
    scene = build_scene(look)
    mouth = scene.framing["mouth"]
    bg = parse_background("#2a2c33")
    out = []
    verts, norms = scene.frame(sim.positions[k], sim.jaw_angle[k], tongue=pose)
    for az, el, half in ((0.0, 0.0, 0.016), (35.0, 4.0, 0.016)):
        cam = Camera(view_rotation(az, el), mouth, half, (SIZE, SIZE), 1.2)
        out.append(render_panel(scene, verts, norms, cam, background=bg)[..., :3])
    # the tongue and the far half of the teeth alone, from the side
    rot = view_rotation(90.0, 0.0)
    near = np.sign((rot.T @ np.array([0.0, 0.0, 1.0]))[0])  # the camera's side of the midline
    keep = [p for p in scene.parts if p.name == "tongue"]
    for p in scene.parts:
        if p.name in ("upper_teeth", "lower_teeth"):
            far = (p.rest[p.faces, 0].mean(axis=1) * near) < 0
            keep.append(replace(p, faces=p.faces[far]))
    inner = _pack(keep, look)
    v, n = inner.frame(look.rest, sim.jaw_angle[k], tongue=pose)
    cam = Camera(rot, mouth + np.array([0.0, -0.004, -0.022]), 0.026, (SIZE, SIZE), 1.2)
    img = render_panel(inner, v, n, cam, background=bg)[..., :3].copy()
    rest, _ = inner.frame(look.rest, sim.jaw_angle[k])
    i = [p.name for p in inner.parts].index("tongue")
    outline = cam.project(rest[inner.offsets[i]:inner.offsets[i + 1]])
    xy = np.round(outline[:, :2]).astype(int)
    ok = (xy[:, 0] >= 0) & (xy[:, 0] < SIZE) & (xy[:, 1] >= 0) & (xy[:, 1] < SIZE)
    img[xy[ok, 1], xy[ok, 0]] = (150, 150, 150)
    out.append(img)
    return out, pose


def main(argv=None) -> int:
    import matplotlib.figure as mfig

    from facemech import default_face

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-o", "--output", type=Path,
                    default=Path(__file__).resolve().parent.parent / "docs/img/tongue.jpg")
    args = ap.parse_args(argv)
    face = default_face()
    fig = mfig.Figure(figsize=(7.5, 5.3), dpi=120)
    titles = ("front", "three-quarter",
              "tongue and the far teeth, profile\n(grey dots: the rest tongue)")
    for r, (label, labels, edges, when) in enumerate(CASES):
        panels, pose = _panels(face, labels, edges, when)
        for c, img in enumerate(panels):
            ax = fig.add_subplot(2, 3, 3 * r + c + 1)
            ax.imshow(img)
            ax.set_xticks([])
            ax.set_yticks([])
            if r == 0:
                ax.set_title(titles[c], fontsize=8)
            if c == 0:
                ax.set_ylabel(f"{label}\nprotrusion {pose[0] * 1e3:.1f} mm\n"
                              f"elevation {pose[1] * 1e3:.1f} mm", fontsize=8)
    fig.tight_layout()
    args.output.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.output, dpi=120, pil_kwargs={"quality": 85})
    print(args.output)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
