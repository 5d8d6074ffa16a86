"""ARKit blendshapes from the model's own gestures: the 52 named shapes, the fit of their weights
(a twin: weights made up, fitted back), the glTF with named targets read by an independent decoder
(pygltflib) and by Blender's own glTF importer (the bpy package, when its interpreter is there),
and the command line."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pygltflib
import pytest
from scipy.spatial import cKDTree

from conftest import activity, run_cli
from facemech import load_face, simulate, write_results
from facemech.analysis.blendshapes import (
    ARKIT_SHAPES,
    RECIPES,
    arkit_basis,
    facs_of,
    fit_weights,
    stem,
    synthesise,
)
from facemech.errors import InputError
from facemech.io.blendshapes import read_weights_csv, write_blendshape_gltf
from facemech.physics.model import model as face_model
from test_export import Glb

#: its module fixtures take 20 s and more: the whole module is slow
pytestmark = pytest.mark.slow

FRAMES = 25
#: the fit's stated error over the lips on this module's result (coarse face), mm (measured 0.76)
LIPS_RMS_MM = 1.0
FACE_RMS_MM = 1.5  # the same over every epidermal node (measured 1.10)
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def basis():
    return arkit_basis(face_model(load_face("default-coarse")))


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    """The coarse face's lips rounding and the jaw opening 8 degrees, then a smile."""
    ramp = np.clip(np.arange(FRAMES) / 10.0, 0.0, 1.0)[:, None]
    act = activity(FRAMES, OOS=0.4, OOI=0.4, DLI=0.3) * ramp
    act[15:] = activity(FRAMES - 15, ZYG=0.6, LAO=0.6)
    sim = simulate(face_model(load_face("default-coarse")), act, np.radians(8.0) * ramp[:, 0])
    path = tmp_path_factory.mktemp("blend") / "r.nc"
    write_results(path, sim)
    return path, sim.positions


def test_the_52_names_their_flags_and_sides(basis):
    assert basis.names == ARKIT_SHAPES and len(set(ARKIT_SHAPES)) == 52
    peak = np.linalg.norm(basis.displacement, axis=2).max(axis=1)
    assert np.all(peak[~basis.made] == 0.0) and np.all(peak[basis.made] > 1e-3)
    made = {n for n, m in zip(basis.names, basis.made, strict=True) if m}
    assert made == {n for n in ARKIT_SHAPES if stem(n)[0] in RECIPES}  # default-coarse: all
    assert "eyeBlinkLeft" not in made and "tongueOut" not in made and "jawOpen" in made
    assert facs_of("mouthSmileRight") == "AU12" and facs_of("jawOpen") == "AU26"
    rows = {r["name"]: r for r in basis.table()}
    assert all(r["gesture"] for r in rows.values())  # each made shape's gesture, or why not
    assert not rows["jawLeft"]["made"] and rows["jawLeft"]["facs"] == "AU30"
    assert "hinge" in rows["jawLeft"]["gesture"] and not rows["cheekPuff"]["made"]
    # a one-sided shape moves its side: +x is the subject's left, as ARKit's Left
    x = basis.rest[:, 0] - np.median(basis.rest[:, 0])
    left = basis.displacement[ARKIT_SHAPES.index("mouthSmileLeft")]
    right = basis.displacement[ARKIT_SHAPES.index("mouthSmileRight")]
    assert np.abs(left[x < -0.01]).max() == 0.0 and np.abs(right[x > 0.01]).max() == 0.0
    both = synthesise(basis, np.eye(52)[[ARKIT_SHAPES.index("mouthSmileLeft")]]
                      + np.eye(52)[[ARKIT_SHAPES.index("mouthSmileRight")]])[0]
    corner = np.argmax(left[:, 1])  # the lip corner lifted most
    assert left[corner, 1] > 3e-3 and np.allclose(both - basis.rest, left + right)


def test_twin_weights_are_recovered(basis):
    """Motion synthesised from known weights (a smile growing over a rounding with the jaw
    open) is fitted back to those weights."""
    rng = np.random.default_rng(5)
    truth = np.zeros((6, 52))
    cols = [ARKIT_SHAPES.index(n) for n in ("jawOpen", "mouthSmileLeft", "mouthSmileRight",
                                            "mouthPucker", "mouthLowerDownLeft",
                                            "browInnerUp", "noseSneerRight")]
    truth[:, cols] = rng.uniform(0.05, 0.95, (6, len(cols)))
    truth[0] = 0.0
    fit = fit_weights(basis, synthesise(basis, truth))
    np.testing.assert_allclose(fit.weights, truth, atol=1e-6)
    assert fit.summary()["rms_face_mm"] < 1e-6
    with pytest.raises(InputError, match="do not match"):
        fit_weights(basis, np.zeros((2, 10, 3)))


def test_weights_reproduce_a_simulated_result(basis, result):
    _, positions = result
    fit = fit_weights(basis, positions)
    assert np.all((fit.weights >= 0) & (fit.weights <= 1))
    s = fit.summary()
    assert s["rms_lips_mm"] < LIPS_RMS_MM and s["rms_face_mm"] < FACE_RMS_MM, s
    moved = np.sqrt(np.mean(np.sum((positions - basis.rest) ** 2, axis=2)[:, basis.lips])) * 1e3
    assert moved > 4 * s["rms_lips_mm"], (moved, s)  # small next to the motion itself
    w = dict(zip(ARKIT_SHAPES, fit.weights[-1], strict=True))
    assert w["mouthSmileLeft"] > 0.2 and w["jawOpen"] > 0.2  # the gestures it was made of


@pytest.fixture(scope="module")
def glb(basis, result, tmp_path_factory):
    _, positions = result
    fit = fit_weights(basis, positions)
    times = np.arange(len(positions)) / 60.0
    path = tmp_path_factory.mktemp("glb") / "face.glb"
    write_blendshape_gltf(path, basis.rest, basis.triangles, ARKIT_SHAPES, basis.displacement,
                          times, fit.weights, {"fit_error": fit.summary()})
    return path, fit


def test_gltf_named_targets_reproduce_the_lips(glb, basis, result):
    """An independent decoder (pygltflib and the spec's accessor rules) gives back 52 named
    targets whose weighted sum reproduces the result's lips within the stated error."""
    path, fit = glb
    g = Glb(path)
    mesh = g.gltf.meshes[0]
    assert mesh.extras["targetNames"] == list(ARKIT_SHAPES)
    prim = mesh.primitives[0]
    assert len(prim.targets) == 52 and len(mesh.weights) == 52
    rest = g.accessor(prim.attributes.POSITION).astype(float)
    targets = np.stack([g.accessor(t["POSITION"]) for t in prim.targets]).astype(float)
    assert g.kind(prim.targets[0]["POSITION"]) == "zero"  # eyeBlinkLeft: flagged, no data
    (anim,) = g.gltf.animations
    assert anim.channels[0].target.path == "weights"
    times = g.accessor(anim.samplers[0].input)
    weights = g.accessor(anim.samplers[0].output).reshape(len(times), 52)
    np.testing.assert_allclose(weights, fit.weights, atol=1e-7)
    _, positions = result
    made = rest + np.einsum("fk,knc->fnc", weights.astype(float), targets)
    lips = np.linalg.norm(made - positions, axis=2)[:, basis.lips] * 1e3
    assert np.sqrt(np.mean(lips ** 2)) < LIPS_RMS_MM
    assert np.sqrt(np.mean(lips ** 2)) == pytest.approx(fit.summary()["rms_lips_mm"], abs=1e-3)


def _blender_python() -> str | None:
    """Blender's Python: FACEMECH_BLENDER_PYTHON, else .venv-blender in the checkout."""
    path = os.environ.get("FACEMECH_BLENDER_PYTHON") or str(ROOT / ".venv-blender/bin/python")
    return path if Path(path).is_file() else None


@pytest.mark.skipif(_blender_python() is None, reason="no Blender (bpy) interpreter: bash "
                    "tools/blender_venv.sh, or FACEMECH_BLENDER_PYTHON")
def test_blender_imports_the_named_targets_and_their_animation(glb, basis, result):
    """Blender's glTF importer makes 52 shape keys named as ARKit's, keys their values at the
    frames' times, and its evaluated mesh at a frame is the result's skin within the error."""
    path, fit = glb
    picks = [0, 12, FRAMES - 1]
    run = subprocess.run([_blender_python(), str(ROOT / "tests/blender_probe.py"), str(path),
                          *map(str, picks)], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    probe = json.loads(run.stdout.split("PROBE", 1)[1])
    assert probe["shape_keys"] == list(ARKIT_SHAPES) and probe["meshes"] == 1
    for name, keys in probe["keyframes"].items():  # Blender keys the weights of each frame
        k = ARKIT_SHAPES.index(name)
        values = np.array(keys)[:, 1]
        np.testing.assert_allclose(values, fit.weights[:, k], atol=1e-6)
    frames = np.array(probe["keyframes"]["jawOpen"])[:, 0]
    np.testing.assert_allclose(np.diff(frames), probe["fps"] / 60.0, rtol=1e-5)
    _, positions = result
    # Blender may order the vertices its own way: match them by rest position and jawOpen's
    # target together (a lower-lip node and its upper-lip twin share their rest position)
    jaw = ARKIT_SHAPES.index("jawOpen")
    tree = cKDTree(np.hstack([basis.rest, basis.displacement[jaw]]))
    blender = np.hstack([np.array(probe["blocks"]["Basis"]),
                         np.array(probe["blocks"]["jawOpen"]) - probe["blocks"]["Basis"]])
    dist, order = tree.query(blender)
    assert dist.max() < 1e-6 and len(set(order)) == len(order) == probe["vertices"]
    lips = basis.lips[order]
    for k in picks:
        pts = np.array(probe["frames"][str(k)])
        err = np.linalg.norm(pts - positions[k][order], axis=1)[lips] * 1e3
        # each frame's lips as the fit reported them (its worst frame bounds them all)
        assert np.sqrt(np.mean(err ** 2)) == pytest.approx(fit.rms_lips_mm[k], abs=0.01)
        assert np.sqrt(np.mean(err ** 2)) < fit.summary()["max_frame_rms_lips_mm"] + 0.01


def test_cli_blendshapes(basis, result, tmp_path, monkeypatch, capsys):
    """The command writes the glTF, CSV and JSON and prints the fit's error (the basis is the
    module's: the command makes the same one from the result's face and preset)."""
    import facemech.analysis.blendshapes as blendshapes

    monkeypatch.setattr(blendshapes, "arkit_basis", lambda *a, **k: basis)
    path, positions = result
    out = tmp_path / "face.glb"
    code, text, err = run_cli(monkeypatch, capsys, "export", path, "--blendshapes", "arkit",
                              "-o", out)
    assert code == 0, err
    assert "27 of 52 made, 25 flagged" in text and "fit error (RMS): lips" in text
    names, times, weights = read_weights_csv(tmp_path / "face.csv")
    assert names == list(ARKIT_SHAPES) and weights.shape == (FRAMES, 52)
    np.testing.assert_allclose(times, np.arange(FRAMES) / 60.0, atol=1e-6)
    doc = json.loads((tmp_path / "face.json").read_text())
    assert doc["names"] == list(ARKIT_SHAPES) and len(doc["shapes"]) == 52
    assert 0 < doc["fit_error"]["rms_lips_mm"] < LIPS_RMS_MM
    per_frame = np.array(doc["frame_error"]["rms_lips_mm"])
    assert per_frame.shape == (FRAMES,) and per_frame.max() == pytest.approx(
        doc["fit_error"]["max_frame_rms_lips_mm"], abs=1e-3)
    np.testing.assert_allclose(doc["weights"], weights, atol=1e-6)
    assert f"lips {doc['fit_error']['rms_lips_mm']:.3f} mm" in text
    assert pygltflib.GLTF2().load(str(out)).meshes[0].extras["targetNames"][17] == "jawOpen"
    for args, field in ((["--blendshapes", "faces", "-o", tmp_path / "x.glb"], "--blendshapes"),
                        (["--blendshapes", "arkit", "-o", tmp_path / "x.obj"], "-o"),
                        (["--blendshapes", "arkit", "--face", tmp_path / "no.npz", "-o",
                          tmp_path / "x.glb"], "--face"),
                        (["--face", "default", "-o", tmp_path / "x.glb"], "--face")):
        code, _, err = run_cli(monkeypatch, capsys, "export", path, *args)
        assert code == 2 and field in err and "Traceback" not in err
    assert not (tmp_path / "x.glb").exists() and not (tmp_path / "x.csv").exists()
