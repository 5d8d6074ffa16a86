"""Reproduce a planned sentence blowing up on a scan talker, and show where its tissue folds.

``python tools/scan_blowup.py FACE.npz "Five wives moved the map away." [--save controls.npz]``

The sentence is synthesised (eSpeak NG) and planned as ``facemech speak`` plans it; the
simulation that blows up has its controls saved (``--save``), and is run again up to a few
frames before the blow-up: for each of those frames, the prisms whose volume has fallen
furthest (volume over rest volume; negative: inverted), where they lie (mm, the face's
frame), and the fastest nodes. Also prints the face's worst prisms at rest: their shape
(height over the top triangle's size) and fill (volume over area x height).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np


def prism_shapes(face) -> tuple[np.ndarray, np.ndarray]:
    """(p,) height over the square root of the top triangle's area, and volume over
    area x height, of a face's prisms at rest."""
    from facemech.geometry.prism import rest_geometry

    rest, pn = face.rest_positions, face.prism_nodes
    vol, _ = rest_geometry(rest, pn)
    tri = rest[pn[:, :3]]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    height = np.linalg.norm(rest[pn[:, 3:]] - rest[pn[:, :3]], axis=2).mean(axis=1)
    return height / np.sqrt(area), vol / (area * height)


def planned_controls(model, text: str):
    """The controls of the planner's simulation that blows up, with its frame; None if none."""
    import facemech.solvers.forward as forward
    from facemech.errors import SimulationBlowUp
    from facemech.speech.planning import plan_controls
    from facemech.speech.tts import synthesize
    from facemech.workflows.speak import LEAD_IN_S, TAIL_S, _padded

    speech = synthesize(text, voice="en-us", rate_wpm=160)
    _, _, alignment = _padded(speech.audio, speech.sample_rate, speech.alignment, LEAD_IN_S,
                              TAIL_S)
    simulate, caught = forward.simulate, []

    def watched(m, activity, jaw=None, **kw):
        try:
            return simulate(m, activity, jaw, **kw)
        except SimulationBlowUp as exc:
            caught.append((np.asarray(activity), np.asarray(jaw), exc.frame))
            raise

    forward.simulate = watched
    try:
        plan_controls(alignment, model)
    except SimulationBlowUp:
        pass
    finally:
        forward.simulate = simulate
    return caught[0] if caught else None


def main(argv=None) -> int:
    from facemech.geometry.prism import rest_geometry
    from facemech.params import preset_pair
    from facemech.physics.model import model as face_model
    from facemech.solvers.forward import simulate

    ap = argparse.ArgumentParser()
    ap.add_argument("face")
    ap.add_argument("text")
    ap.add_argument("--save")
    args = ap.parse_args(argv)
    params, steps = preset_pair("anatomical")
    model = face_model(args.face, params, steps=steps)
    face = model.face
    aspect, fill = prism_shapes(face)
    centre = face.rest_positions[face.prism_nodes].mean(axis=1) * 1e3
    worst = np.argsort(fill)[:5]
    print("at rest: prisms' height / sqrt(area) max", round(float(aspect.max()), 2),
          "; fill min", round(float(fill.min()), 3), "at", centre[worst].round(0).tolist())
    found = planned_controls(model, args.text)
    if found is None:
        print("no blow-up")
        return 0
    activity, jaw, frame = found
    print("blew up at frame", frame)
    if args.save:
        np.savez(args.save, activity=activity, jaw=jaw, frame=frame)
    rest_vol, _ = rest_geometry(face.rest_positions, face.prism_nodes)
    for k in (frame - 12, frame - 4, frame - 1):
        state = simulate(model, activity[:k], jaw[:k]).final_state
        vol, _ = rest_geometry(state.positions, face.prism_nodes)
        ratio = vol / rest_vol
        low = np.argsort(ratio)[:3]
        speed = np.linalg.norm(state.velocities, axis=1)
        fast = np.argsort(speed)[-3:]
        print(f"frame {k}: volume ratio {ratio[low].round(2).tolist()} at "
              f"{centre[low].round(0).tolist()} mm (shape {aspect[low].round(1).tolist()}); "
              f"fastest {speed[fast].round(2).tolist()} m/s at "
              f"{(face.rest_positions[fast] * 1e3).round(0).tolist()} mm")
    return 1


if __name__ == "__main__":
    sys.exit(main())
