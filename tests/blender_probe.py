"""Run by Blender's Python (the ``bpy`` package, in a venv of its own: it pins numpy < 2):
import a glTF with Blender's own importer and print, as JSON, what Blender made of it.

    python blender_probe.py FILE.glb K1 K2 ...

prints {"shape_keys": names, "vertices": n, "fps": fps, "keyframes": {name: [[frame, value],
...]}, "frames": {k: (n, 3) evaluated vertex positions at the k-th keyframe}, "blocks": the
vertices of the shape keys "Basis" and "jawOpen"}, in glTF's axes (Blender's are +Z up).
"""

import json
import sys

import bpy


def main(path: str, picks: list[int], match=("jawOpen",)) -> dict:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=path)
    meshes = [o for o in bpy.context.scene.objects if o.type == "MESH"]
    obj = meshes[0]
    keys = obj.data.shape_keys
    names = [b.name for b in keys.key_blocks][1:]  # the first is Blender's "Basis"
    action = keys.animation_data.action if keys.animation_data else None
    curves = {}
    if action is not None:
        for fc in _fcurves(action, keys):
            name = fc.data_path.split('"')[1]
            curves[name] = [[p.co[0], p.co[1]] for p in fc.keyframe_points]
    first = next(iter(curves.values()), [])
    frames = {}
    scene = bpy.context.scene
    for k in picks:
        f = first[k][0]
        scene.frame_set(int(f), subframe=f - int(f))
        graph = bpy.context.evaluated_depsgraph_get()
        evaluated = obj.evaluated_get(graph)
        mesh = evaluated.to_mesh()
        world = evaluated.matrix_world
        pts = [world @ v.co for v in mesh.vertices]
        frames[k] = [[p.x, p.z, -p.y] for p in pts]  # Blender's +Z up back to glTF's +Y up
        evaluated.to_mesh_clear()
    blocks = {b.name: [[v.co.x, v.co.z, -v.co.y] for v in b.data]
              for b in keys.key_blocks if b.name in ("Basis", *match)}
    return {"shape_keys": names, "vertices": len(obj.data.vertices), "blocks": blocks,
            "fps": scene.render.fps / scene.render.fps_base, "keyframes": curves,
            "frames": frames, "meshes": len(meshes)}


def _fcurves(action, keys):
    """The action's F-curves: Blender 4.4+ keeps them in layers, slots and channel bags."""
    if hasattr(action, "fcurves") and len(action.fcurves):
        return list(action.fcurves)
    out = []
    for layer in getattr(action, "layers", []):
        for strip in layer.strips:
            for bag in strip.channelbags:
                out.extend(bag.fcurves)
    return out


if __name__ == "__main__":
    print("PROBE" + json.dumps(main(sys.argv[1], [int(a) for a in sys.argv[2:]])))
