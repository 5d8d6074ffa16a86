"""An interactive viewer: one self-contained HTML page (WebGL, no network) of a results file.

The page holds its template (``viewer_template.html``, shipped with the package) and a data
block, ``<script id="facemech-data" type="application/json">``, that :func:`viewer_data` fills
(format ``"facemech-viewer/1"``: the skin's positions quantised as int16 about the rest shape,
|error| <= q / 2, the markers, measured markers, activity, jaw and tongue tip per frame, and
the whole head as :func:`scene_block` packs :func:`facemech.viz.scene.build_scene`). Binary
arrays are base64, little-endian and C-ordered; every key, its shape and unit:
docs/viewer.md, "The data block". Measured markers are matched to the model's by name,
linearly interpolated onto the results' times, and left out (NaN) outside their own time span
and across their gaps: nothing is extrapolated.
"""

from __future__ import annotations

import base64
import html
import io
import json
from importlib import resources
from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from ..errors import InputError
from ..io.results import results_tongue
from ..params import FRAME_RATE_HZ

FORMAT = "facemech-viewer/1"
DATA_ID = "facemech-data"
_PLACEHOLDER = "/*FACEMECH_DATA*/"
_TITLE_PLACEHOLDER = "<!--FACEMECH_TITLE-->"
ATLAS_MAX_SIDE = 4096  #: texels; larger atlases are scaled down (WebGL's common limit)
PNG_BUDGET = 2_000_000  #: bytes; a larger colour atlas goes as JPEG
_UV_ONE = 65535


def _b64(a: np.ndarray, dtype: str) -> str:
    return base64.b64encode(np.ascontiguousarray(a, dtype=np.dtype(dtype).newbyteorder("<"))
                            .tobytes()).decode("ascii")


def quantise(positions: np.ndarray, rest: np.ndarray) -> tuple[np.ndarray, float]:
    """Positions as int16 steps around a rest shape.

    Parameters
    ----------
    positions : (frames, nodes, 3) m
    rest : (nodes, 3) m

    Returns
    -------
    steps : (frames, nodes, 3) int16, positions = rest + scale * steps
    scale : m per step (the largest displacement over 32000, at least 1 nm); the error is at most
        scale / 2
    """
    delta = np.asarray(positions, float) - np.asarray(rest, float)[None]
    biggest = float(np.max(np.abs(delta))) if delta.size else 0.0
    scale = max(biggest / 32000.0, 1e-9)
    return np.round(delta / scale).astype(np.int16), scale


def resample_measured(measured, names: list[str], time: np.ndarray) -> tuple[np.ndarray, list]:
    """Measured trajectories of the named markers on the results' times.

    Linear interpolation between measured samples; NaN outside the measured time span (give or
    take 1 % of a sample period, for times rounded in the file) and wherever either neighbouring
    sample is missing (gaps are not bridged, nothing extrapolated).

    Parameters
    ----------
    measured : :class:`~facemech.markerset.MarkerSet`
    names : markers to take, all in ``measured.names``
    time : (frames,) s, the results' times

    Returns
    -------
    positions : (frames, len(names), 3) m
    coverage : [first, last] s of the results' times that have any measured sample, or [] if none
    """
    t = np.asarray(measured.time, float)
    time = np.asarray(time, float)
    out = np.full((len(time), len(names), 3), np.nan)
    tol = 0.01 / measured.rate  # 1 % of a sample: times rounded in the file still count
    inside = ((time >= t[0] - tol) & (time <= t[-1] + tol) if len(t)
              else np.zeros(len(time), bool))
    for j, name in enumerate(names):
        p = measured.marker(name)
        ok = np.all(np.isfinite(p), axis=1)
        if len(t) < 2:
            continue
        both = np.interp(time, t, ok.astype(float)) > 1.0 - 1e-9
        keep = inside & both
        for a in range(3):
            out[keep, j, a] = np.interp(time[keep], t, np.where(ok, p[:, a], 0.0))
    have = np.any(np.isfinite(out[..., 0]), axis=1)
    coverage = [float(time[have][0]), float(time[have][-1])] if have.any() else []
    return out, coverage


def linear_to_srgb8(c: np.ndarray) -> np.ndarray:
    """Linear light in [0, 1] to 8-bit sRGB (the inverse of :func:`~.raster.srgb_to_linear`)."""
    c = np.clip(np.asarray(c, float), 0.0, 1.0)
    s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)
    return np.round(s * 255.0).astype(np.uint8)


def _image_uri(pixels: np.ndarray, mode: str, fmt: str) -> str:
    from PIL import Image

    buf = io.BytesIO()
    im = Image.fromarray(pixels, mode)
    if fmt == "JPEG":
        im.save(buf, "JPEG", quality=92)
    else:
        im.save(buf, "PNG")  # zlib's default level: optimize=True searches long for little
    return f"data:image/{fmt.lower()};base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def atlas_block(atlas: np.ndarray) -> dict:
    """The texture atlas (H, W, 4) linear RGBA as data URIs: the ``scene.atlas`` of the data
    block (docs/viewer.md, "The data block")."""
    from PIL import Image

    rgb = linear_to_srgb8(atlas[..., :3])
    alpha = np.round(np.clip(atlas[..., 3], 0, 1) * 255).astype(np.uint8)
    h, w = rgb.shape[:2]
    k = min(1.0, ATLAS_MAX_SIDE / max(h, w))
    if k < 1.0:  # normalised coordinates: the triangles' uv need no change
        size = (max(1, round(w * k)), max(1, round(h * k)))
        rgb = np.asarray(Image.fromarray(rgb, "RGB").resize(size, Image.LANCZOS))
        alpha = np.asarray(Image.fromarray(alpha, "L").resize(size, Image.BILINEAR))
        h, w = rgb.shape[:2]
    color = _image_uri(rgb, "RGB", "PNG")
    if len(color) > PNG_BUDGET:
        color = _image_uri(rgb, "RGB", "JPEG")
    return {"width": int(w), "height": int(h), "color": color,
            "alpha": _image_uri(alpha, "L", "PNG") if alpha.min() < 255 else None}


def scene_block(scene) -> dict:
    """The data block's ``scene`` (docs/viewer.md) of a
    :class:`~facemech.viz.scene.Scene`."""
    from .raster import GROUND, INSIDE, LIGHTS, SKY, WRAP
    from .scene import SKIRT_DEPTH

    n = len(scene.albedo)
    tris = np.asarray(scene.tris)
    idx = "uint16" if n <= 65535 else "uint32"
    tex = np.asarray(scene.tex) > 0
    flags = (tex.astype(np.uint8) | (np.asarray(scene.alpha_test, bool) << 1)
             | (np.asarray(scene.two_sided, bool) << 2)).astype(np.uint8)
    h, w = scene.atlas.shape[:2]
    uv = np.asarray(scene.uv, float)[tex] / np.array([w, h])
    uv = np.round(np.clip(uv, 0.0, 1.0) * _UV_ONE)
    parts, face = [], 0
    for i, p in enumerate(scene.parts):
        g = np.asarray(p.gloss, float)
        part = {"name": p.name, "motion": p.motion, "inward": bool(p.inward),
                "start": int(scene.offsets[i]), "count": len(p.rest),
                "faceStart": face, "faceCount": len(p.faces),
                "gloss": [float(v) for v in (g if g.ndim == 1 else g.mean(axis=0))],
                "framed": p.name in ("skin", "head", "hair")}
        if p.motion == "skirt":  # from the skin's edge nodes in towards the head's centre
            part.update(nodes=_b64(p.skirt_nodes, "u4"),
                        centre=[float(v) for v in scene.centre], depth=SKIRT_DEPTH)
        if g.ndim == 2:  # per vertex (the skin's moist lips)
            part["glossVertex"] = _b64(g, "f4")
        if p.motion == "follow":  # the head closing the skin (:mod:`.closure`)
            c = p.follow
            part.update(nodes=_b64(c.nodes, "u4"), inner=_b64(c.inner, "u4"),
                        weights=_b64(c.weights, "f4"), reach=_b64(c.reach, "f4"))
        if p.name == "tongue" and scene.tongue_modes is not None:  # its tip's bending
            part["modes"] = _b64(scene.tongue_modes, "f4")
        parts.append(part)
        face += len(p.faces)
    rest = np.concatenate([p.rest for p in scene.parts])
    pts = scene.framing["points"]
    dirs = LIGHTS[:, :3] / np.linalg.norm(LIGHTS[:, :3], axis=1, keepdims=True)
    return {
        "nVertices": int(n),
        "rest": _b64(rest, "f4"),
        "triangles": {"dtype": idx, "data": _b64(tris, "u2" if idx == "uint16" else "u4")},
        "flags": _b64(flags, "u1"),
        "uv": _b64(uv, "u2"),
        "albedo": _b64(linear_to_srgb8(scene.albedo), "u1"),
        "atlas": atlas_block(scene.atlas),
        "parts": parts,
        "hinge": {"point": [float(v) for v in scene.look.hinge_point],
                  "axis": [float(v) for v in scene.look.hinge_axis]},
        "frameY": [float(pts[:, 1].min()), float(pts[:, 1].max())],
        "light": {"dirs": dirs.round(6).tolist(), "intensity": LIGHTS[:, 3].tolist(),
                  "sky": SKY, "ground": GROUND, "wrap": WRAP, "inside": list(INSIDE)},
    }


def decode_atlas(block: dict) -> np.ndarray:
    """The atlas of :func:`atlas_block` back as (H, W, 4) float32 linear RGBA."""
    from PIL import Image

    from .raster import srgb_to_linear

    def image(uri):
        return np.asarray(Image.open(io.BytesIO(base64.b64decode(uri.split(",", 1)[1]))))

    rgb = srgb_to_linear(image(block["color"])[..., :3] / 255.0)
    alpha = (image(block["alpha"]) / 255.0 if block["alpha"] is not None
             else np.ones(rgb.shape[:2]))
    return np.dstack([rgb, alpha]).astype(np.float32)


def decode_scene(block: dict) -> dict:
    """The arrays of a data block's ``scene``, as :class:`~facemech.viz.scene.Scene` has them.

    Returns
    -------
    dict with ``rest`` (N, 3) m, ``tris`` (F, 3), ``tex``, ``alpha_test``, ``two_sided`` (F,)
    bool, ``uv`` (F, 3, 2) atlas texels (zero where untextured), ``albedo`` (N, 3) linear,
    ``atlas`` (H, W, 4) linear RGBA, ``offsets`` (parts + 1,), ``gloss`` (N, 2)
    """
    from .raster import srgb_to_linear

    n = block["nVertices"]
    tris = decode(block["triangles"], block["triangles"]["dtype"], (-1, 3))
    flags = decode(block["flags"], "u1")
    tex = (flags & 1) > 0
    h, w = block["atlas"]["height"], block["atlas"]["width"]
    uv = np.zeros((len(tris), 3, 2))
    uv[tex] = decode(block["uv"], "u2", (-1, 3, 2)) / _UV_ONE * np.array([w, h])
    parts = block["parts"]
    gloss = np.concatenate([decode(p["glossVertex"], "f4", (-1, 2)) if "glossVertex" in p
                            else np.tile(np.float32(p["gloss"]), (p["count"], 1))
                            for p in parts])
    return {"rest": decode(block["rest"], "f4", (n, 3)), "tris": tris, "tex": tex,
            "alpha_test": (flags & 2) > 0, "two_sided": (flags & 4) > 0, "uv": uv,
            "albedo": srgb_to_linear(decode(block["albedo"], "u1", (n, 3)) / 255.0),
            "atlas": decode_atlas(block["atlas"]),
            "offsets": np.array([p["start"] for p in parts] + [n]), "gloss": gloss}


def _measured_block(measured, mk_names: list[str], time: np.ndarray, frames: int) -> dict:
    """The page's block of measured markers: those whose names the model's markers share,
    interpolated onto the results' times, with a note on how they were matched; InputError
    naming ``markers`` when no name is shared."""
    shared = [n for n in mk_names if n in measured.names]
    if not shared:
        raise InputError(f"no marker name in common with the model's ({', '.join(mk_names[:8])}"
                         f"{', ...' if len(mk_names) > 8 else ''})",
                         source=measured.meta.get("source"), field="markers")
    mp, coverage = resample_measured(measured, shared, time)
    t = np.asarray(measured.time, float)
    note = (f"{len(shared)} of {measured.n_markers} measured markers match the model's by "
            f"name; measured {t[0]:.3f}-{t[-1]:.3f} s at {measured.rate:.4g} Hz, linearly "
            f"interpolated onto the results' {frames} frames")
    if not coverage:
        note += "; no measured sample falls inside the results' time span"
    elif coverage[0] > time[0] + 1e-9 or coverage[-1] < time[-1] - 1e-9:
        note += f"; shown only for {coverage[0]:.3f}-{coverage[1]:.3f} s"
    return {"names": shared, "data": _b64(mp, "f4"),
            "source": str(measured.meta.get("source", "")), "coverage": coverage,
            "note": note}


def viewer_data(results, measured=None, title: str | None = None) -> dict:
    """The JSON-ready data block of the page (its keys: docs/viewer.md, "The data block").

    Parameters
    ----------
    results : xarray.Dataset from :func:`facemech.io.results.read_results`
    measured : :class:`~facemech.markerset.MarkerSet` or None; markers whose names the model
        also has are shown beside the model's
    title : page title (default: the dataset's ``face`` and ``preset`` attributes)
    """
    src = results.encoding.get("source")
    pos = np.asarray(results["positions"].transpose("time", "node", "axis").values, float)
    frames, nodes = pos.shape[:2]
    if frames == 0 or nodes == 0 or not np.all(np.isfinite(pos)):
        raise InputError("no frames, no nodes or non-finite positions", source=src,
                         field="positions")
    tri = np.asarray(results["triangles"].values)
    if tri.ndim != 2 or tri.shape[1] != 3 or tri.size == 0 or tri.min() < 0 \
            or tri.max() >= nodes:
        raise InputError(f"triangles must be (n, 3) indices below {nodes}", source=src,
                         field="triangles")
    rest = (np.asarray(results["rest_positions"].values, float)
            if "rest_positions" in results else pos[0])
    if rest.shape != (nodes, 3) or not np.all(np.isfinite(rest)):
        rest = pos[0]
    time = (np.asarray(results["time"].values, float) if "time" in results.coords
            else np.arange(frames) / float(results.attrs.get("frame_rate_hz", FRAME_RATE_HZ)))
    rate = float(results.attrs.get("frame_rate_hz", 0.0) or 0.0)
    if not rate > 0:
        rate = 1.0 / float(np.median(np.diff(time))) if frames > 1 else FRAME_RATE_HZ
    steps, scale = quantise(pos, rest)

    mk = np.asarray(results["markers"].transpose("time", "marker", "axis").values, float)
    mk_names = [str(m) for m in results["marker"].values]
    if "activity" in results:
        act = np.asarray(results["activity"].transpose("time", "muscle").values, float)
        muscles = [str(m) for m in results["muscle"].values]
    else:
        act, muscles = np.zeros((frames, 0)), []
    jaw = (np.degrees(np.asarray(results["jaw_angle"].values, float)) if "jaw_angle" in results
           else np.zeros(frames))
    jaw_shift = (np.asarray(results["jaw_shift"].transpose("time", "shift_axis").values, float)
                 if "jaw_shift" in results else np.zeros((frames, 2)))
    tongue = results_tongue(results)
    tongue = np.zeros((frames, 2)) if tongue is None else tongue

    meas_block = None if measured is None else _measured_block(measured, mk_names, time, frames)

    from .scene import build_scene, look_from_dataset

    scene = build_scene(look_from_dataset(results))
    if scene.parts[0].motion != "skin" or len(scene.parts[0].rest) != nodes:
        raise InputError("the scene's skin does not match the positions", source=src,
                         field="positions")

    undetermined, warning = undetermined_muscles(results)
    if title is None:
        parts = [str(results.attrs.get(k)) for k in ("face", "preset") if results.attrs.get(k)]
        title = "facemech: " + (", ".join(parts) if parts else "results")
    return {
        "format": FORMAT,
        "title": str(title),
        "frameRate": rate,
        "time": [float(v) for v in time],
        "nNodes": int(nodes),
        "triangles": {"dtype": "uint16" if nodes <= 65535 else "uint32",
                      "data": _b64(tri, "u2" if nodes <= 65535 else "u4")},
        "rest": _b64(rest, "f4"),
        "positions": {"dtype": "int16", "scale": scale, "data": _b64(steps, "i2")},
        "markers": {"names": mk_names, "data": _b64(mk, "f4")},
        "measured": meas_block,
        "activity": {"names": muscles, "data": _b64(act, "f4"), "undetermined": undetermined},
        "warning": warning,
        "jawDeg": _b64(jaw, "f4"),
        "jawShift": _b64(jaw_shift, "f4"),
        "tongueTip": _b64(tongue, "f4"),
        "scene": scene_block(scene),
    }


def undetermined_muscles(results) -> tuple[list[str], str | None]:
    """(the muscles an inversion's markers do not determine alone, the page's warning or
    None), from the results' ``regularised`` and ``combinations_determined`` attributes."""
    names = [n for n in str(results.attrs.get("regularised", "")).split(",") if n]
    if not names:
        return [], None
    det = [n for n in str(results.attrs.get("combinations_determined", "")).split(",") if n]
    return [n for n in names if n != "jaw"], (
        f"not determined by the markers alone, their activity follows the inversion's "
        f"regularisation: {', '.join(names)}; the markers measure "
        f"{'; '.join(det) if det else 'none of their combinations within 0.1'}")


def template() -> str:
    """The page template (HTML, CSS and JavaScript) shipped with the package."""
    return resources.files("facemech.viz").joinpath("viewer_template.html").read_text("utf-8")


def render_html(data: dict) -> str:
    """The page: the template with ``data`` in its data block (``</`` escaped)."""
    block = json.dumps(data, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")
    page = template()
    if _PLACEHOLDER not in page:
        raise RuntimeError("viewer template has no data placeholder")
    page = page.replace(_TITLE_PLACEHOLDER, html.escape(data["title"]))
    return page.replace(_PLACEHOLDER, block)


def read_data_block(page: str) -> dict:
    """The data block of a page written by :func:`write_viewer` (for tests and tools)."""
    start_tag = f'<script id="{DATA_ID}" type="application/json">'
    i = page.index(start_tag) + len(start_tag)
    j = page.index("</script>", i)
    return json.loads(page[i:j])


def decode(block, dtype: str, shape=None) -> np.ndarray:
    """A base64 array of the data block as numpy (``block`` a string or ``{"data": ...}``)."""
    text = block["data"] if isinstance(block, dict) else block
    a = np.frombuffer(base64.b64decode(text), dtype=np.dtype(dtype).newbyteorder("<"))
    return a.reshape(shape) if shape is not None else a


def write_viewer(results, path: str | Path, measured=None, title: str | None = None) -> Path:
    """Write the interactive viewer page of a results dataset.

    The page is one HTML file that works offline: the movie renderer's head (skin, eyes, teeth,
    tongue, oral cavity, head shell with hair, ears) in WebGL with orbit, zoom, play/pause and a
    time slider at the real frame rate, the model's markers (and measured ones) with names on
    hover, and a plot of muscle activity and jaw angle against time that follows and seeks.

    Parameters
    ----------
    results : xarray.Dataset from :func:`facemech.io.results.read_results`
    path : the page (.html), written atomically
    measured : :class:`~facemech.markerset.MarkerSet` or None, in the model's frame (metres)
    title : page title

    Returns
    -------
    The path written.
    """
    page = render_html(viewer_data(results, measured=measured, title=title))
    path = Path(path)
    with atomic_path(path, suffix=".html") as tmp:
        tmp.write_text(page, encoding="utf-8")
    return path


def view_file(result: str | Path, output: str | Path, markers: str | Path | None = None,
              units: str | None = None, title: str | None = None) -> Path:
    """Read a results file (and measured markers) and write its viewer page.

    Parameters
    ----------
    result : results file (.nc) written by facemech
    output : the page (.html or .htm); never one of the inputs
    markers : measured marker file (.csv, .trc, .c3d, .tsv), optional, in the model's frame
    units : length unit of the marker file when it names none (e.g. ``mm``)
    title : page title (default: the results file's name, face and preset)
    """
    from ..io.markers import read_markers
    from ..io.results import read_results

    result, output = Path(result), Path(output)
    if output.suffix.lower() not in (".html", ".htm"):
        raise InputError("the page must end in .html", source=str(output), field="output")
    for inp in (result, markers):
        if inp is not None and Path(inp).exists() and output.exists() \
                and output.resolve() == Path(inp).resolve():
            raise InputError("refusing to overwrite an input", source=str(output),
                             field="output")
    if units is not None and markers is None:
        raise InputError("--units applies to --markers only", field="units")
    ds = read_results(result)
    measured = read_markers(markers, units=units) if markers is not None else None
    if title is None:
        parts = [str(ds.attrs.get(k)) for k in ("face", "preset") if ds.attrs.get(k)]
        title = result.name + (f" ({', '.join(parts)})" if parts else "")
    return write_viewer(ds, output, measured=measured, title=title)
