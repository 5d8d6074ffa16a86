"""Anthropometric measures of the drawn head at rest (Farkas' landmarks), in millimetres.

Measured on what the renderer draws (the drawn skin, :mod:`.shape`; the closing head; the
nasal base, :mod:`.nose`), at rest:

* head length g-op: glabella (the most forward midline point of the forehead, up to 30 mm
  over the nasion) to opisthocranion (the most posterior midline point of the head, above
  30 mm under the nasion), along z;
* face height n-gn: nasion to gnathion (the midline chin point furthest from the nasion, not
  under the menton nor behind it);
* nose width al-al: the alae's lateral extent (where the nasal base's relief rises 0.2 mm);
* mouth width ch-ch: cheilion to cheilion (the drawn skin's nodes at the mouth corners).

:data:`FARKAS` holds the adult male norms (mean, SD) they are compared with.
"""

from __future__ import annotations

import numpy as np

#: mm, (mean, SD) of young adult North American white men (Farkas, Anthropometry of the Head
#: and Face, 2nd ed., 1994)
FARKAS = {"g-op": (197.0, 6.0), "n-gn": (121.3, 6.8), "al-al": (34.9, 2.1),
          "ch-ch": (54.0, 3.3)}


def head_measures(scene) -> dict[str, float]:
    """Farkas' four measures (mm) of a built-in face's scene (:func:`.scene.build_scene`)."""
    look = scene.look
    lm = look.landmarks
    verts, _ = scene.frame(look.rest)
    names = [p.name for p in scene.parts]
    part = {n: verts[scene.offsets[k]:scene.offsets[k + 1]] for k, n in enumerate(names)}
    skin = part["skin"]
    head = np.concatenate([skin, part.get("head", skin[:0])])
    n = np.asarray(lm["nasion"], float)
    mid = np.abs(head[:, 0] - n[0]) < 0.004
    brow = mid & (head[:, 1] > n[1]) & (head[:, 1] < n[1] + 0.03) & (head[:, 2] > n[2] - 0.03)
    back = mid & (head[:, 1] > n[1] - 0.03)
    g_op = head[brow, 2].max() - head[back, 2].min()
    me = np.asarray(lm["menton"], float)
    chin = ((np.abs(skin[:, 0] - n[0]) < 0.004) & (skin[:, 1] < lm["lower_lip_center"][1])
            & (skin[:, 1] > me[1] - 0.001) & (skin[:, 2] > me[2] - 0.001))
    n_gn = np.linalg.norm(skin[chin] - n, axis=1).max()
    corners = [int(np.argmin(np.linalg.norm(look.rest - lm[k], axis=1)))
               for k in ("mouth_corner_left", "mouth_corner_right")]
    ch_ch = np.linalg.norm(skin[corners[0]] - skin[corners[1]])
    out = {"g-op": g_op, "n-gn": n_gn, "ch-ch": ch_ch}
    if "nostrils" in part:
        p = next(q for q in scene.parts if q.name == "nostrils")
        raised = p.follow.offset[:, 2] > 0.0002
        x = part["nostrils"][raised, 0]
        out["al-al"] = x.max() - x.min()
    return {k: float(v) * 1e3 for k, v in out.items()}
