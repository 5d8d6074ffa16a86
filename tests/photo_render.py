"""The photo tests' shared render: a face built from a photo, drawn through the photo's camera."""

import numpy as np


def rerender(made, size) -> np.ndarray:
    """The talker ``made`` (a photo build) at rest, rendered through the photo's fitted camera
    (frontal), (h, w, 3) sRGB."""
    from facemech.viz.camera import Camera
    from facemech.viz.look import look_from_model
    from facemech.viz.render import parse_background, render_panel
    from facemech.viz.scene import build_scene

    h, w = size
    look = look_from_model(made.model)
    scene = build_scene(look)
    c = made.fit.camera
    target = c.back_project(np.array([[w / 2, h / 2]]), np.array([c.plane_z]))[0]
    cam = Camera(np.eye(3), target, c.metres_per_px * h / 2, (h, w), c.distance)
    verts, norms = scene.frame(look.rest, 0.0)
    return render_panel(scene, verts, norms, cam, background=parse_background("#8a9099"))[
        ..., :3]
