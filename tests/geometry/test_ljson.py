"""menpo's LJSON landmark files, versions 1-3, read into iBUG-68 order by their labels."""

from __future__ import annotations

import json

import numpy as np
import pytest

from facemech.errors import InputError
from facemech.geometry.ibug import generic_ibug68, read_ibug68
from facemech.geometry.scan_ljson import read_ljson_points
from scans import SCAN_ORDER, group, v3

#: menpo's face_ibug_68 labeller: iBUG's own order
MENPO_ORDER = [("jaw", range(0, 17)), ("left_eyebrow", range(17, 22)),
               ("right_eyebrow", range(22, 27)), ("nose", range(27, 36)),
               ("left_eye", range(36, 42)), ("right_eye", range(42, 48)),
               ("mouth", range(48, 68))]


def ibug_mm():
    return generic_ibug68() * 1e3


def write(path, data):
    path.write_text(json.dumps(data))
    return path


def one_line(exc, *needles):
    text = str(exc.value)
    assert "\n" not in text
    for n in needles:
        assert n in text, (n, text)
    return text


# ---- version 3 -------------------------------------------------------------------------------
def test_v3_parts_in_another_order_are_put_in_ibug_order(tmp_path):
    pts = ibug_mm()
    path = write(tmp_path / "scan.ljson", v3(pts))
    raw = json.loads(path.read_text())["groups"]["PTS"]["landmarks"]["points"]
    assert not np.allclose(raw, pts)  # the file's order is not iBUG's
    got = read_ljson_points(path)
    np.testing.assert_allclose(got.points, pts, atol=1e-12)
    assert got.version == 3 and got.field == "groups.PTS.landmarks"
    assert got.by_labels == tuple(n for n, _ in SCAN_ORDER)
    # the right eye's outer corner (iBUG 36) is row 17 of the file: after the 17 chin points
    assert got.rows[36] == 17 and got.rows[17] == 29 and got.rows[48] == 48
    np.testing.assert_allclose(read_ibug68(path), pts * 1e-3, atol=1e-15)


def test_v3_masks_in_any_row_order_and_the_first_group_of_68(tmp_path):
    pts = ibug_mm()
    data = v3(pts, key="face_ibug_68_trimesh", shuffle=3)
    data["groups"] = {"eyes": {"landmarks": {"points": pts[36:48].tolist()}, "labels": []},
                      **data["groups"]}
    got = read_ljson_points(write(tmp_path / "a.ljson", data))
    np.testing.assert_allclose(got.points, pts, atol=1e-12)
    assert got.field == "groups.face_ibug_68_trimesh.landmarks"


def test_menpo_labeller_order_and_boolean_masks_read_as_stored(tmp_path):
    pts = ibug_mm()
    data = v3(pts, order=MENPO_ORDER, key="face_ibug_68")
    for lab in data["groups"]["face_ibug_68"]["labels"]:
        rows = set(lab["mask"])
        lab["mask"] = [k in rows for k in range(68)]
    got = read_ljson_points(write(tmp_path / "m.ljson", data))
    np.testing.assert_allclose(got.points, pts, atol=1e-12)
    np.testing.assert_array_equal(got.rows, np.arange(68))
    # a trimesh group: one label over all points; none: the points as stored
    for labels in ([{"label": "tri", "mask": list(range(68))}], []):
        data = {"version": 3, "groups": {"LJSON": {"landmarks": {"points": pts.tolist()},
                                                   "labels": labels}}}
        got = read_ljson_points(write(tmp_path / "t.ljson", data))
        np.testing.assert_allclose(got.points, pts, atol=1e-12)


def test_eyes_named_from_the_subjects_view_go_by_their_position(tmp_path):
    """A file whose ``leye``/``leyebrow`` are the subject's left (iBUG 42-47, 22-26): the
    jaw's order says which side is which, so the points still land on their iBUG numbers."""
    pts = ibug_mm()
    swapped = [("chin", range(0, 17)), ("leye", range(42, 48)), ("reye", range(36, 42)),
               ("leyebrow", range(22, 27)), ("nose", range(27, 36)),
               ("reyebrow", range(17, 22)), ("mouth", range(48, 68))]
    got = read_ljson_points(write(tmp_path / "s.ljson", v3(pts, order=swapped)))
    np.testing.assert_allclose(got.points, pts, atol=1e-12)
    assert got.points[36, 0] < 0 < got.points[45, 0]  # 36 on the subject's right (-x)


def test_2d_points_are_ordered_and_refused_for_a_scan(tmp_path):
    xy = ibug_mm()[:, :2]
    path = write(tmp_path / "photo.ljson", v3(xy, shuffle=1))
    got = read_ljson_points(path)
    assert got.points.shape == (68, 2)
    np.testing.assert_allclose(got.points, xy, atol=1e-12)
    with pytest.raises(InputError) as exc:
        read_ibug68(path)
    one_line(exc, "photo.ljson: field 'groups.PTS.landmarks'", "2-D iBUG points")


def test_null_points_are_nan_and_refused_for_a_scan_by_their_ibug_number(tmp_path):
    pts = ibug_mm().tolist()
    pts[37] = [None, None, None]
    path = write(tmp_path / "n.ljson", v3(np.array(pts, dtype=object)))
    got = read_ljson_points(path)
    assert np.isnan(got.points[37]).all() and np.isfinite(np.delete(got.points, 37, 0)).all()
    with pytest.raises(InputError) as exc:
        read_ibug68(path)
    one_line(exc, "n.ljson: field 'groups.PTS.landmarks'", "iBUG point 37", "row 18",
             "null")


# ---- versions 1 and 2, as before ---------------------------------------------------------------
def test_v1_and_v2_still_read(tmp_path):
    pts = ibug_mm()
    v2 = {"version": 2, **group(pts, SCAN_ORDER, shuffle=5)}
    np.testing.assert_allclose(read_ljson_points(write(tmp_path / "2.ljson", v2)).points, pts,
                               atol=1e-12)
    plain = {"version": 2, "landmarks": {"points": pts.tolist()}, "labels": []}
    np.testing.assert_allclose(read_ibug68(write(tmp_path / "p.ljson", plain)), pts * 1e-3,
                               atol=1e-15)
    v1 = {"version": 1, "groups": [
        {"label": name, "landmarks": [{"point": p} for p in pts[list(r)].tolist()]}
        for name, r in SCAN_ORDER]}
    got = read_ljson_points(write(tmp_path / "1.ljson", v1))
    np.testing.assert_allclose(got.points, pts, atol=1e-12)
    assert got.version == 1


# ---- bad files: one line naming the file and the field -----------------------------------------
@pytest.mark.parametrize("edit, field, words", [
    (lambda d: d.update(version=7), "version", "versions 1, 2 and 3"),
    (lambda d: d["groups"]["PTS"]["labels"][1].update(mask=[17, 18, 19]),
     "groups.PTS.labels", "'leye' has 3 points"),
    (lambda d: d["groups"]["PTS"]["labels"][1].update(mask=[17, 18, 19, 20, 21, 99]),
     "groups.PTS.labels[1].mask", "out of range"),
    (lambda d: d["groups"]["PTS"]["labels"][6].update(label="teeth"),
     "groups.PTS.labels", "'teeth' is not a part"),
    (lambda d: d["groups"]["PTS"]["labels"][5].update(label="leyebrow"),
     "groups.PTS.labels", "already given"),
    (lambda d: d["groups"]["PTS"]["landmarks"]["points"].pop(),
     "groups", "no group of 68 points"),
    (lambda d: d["groups"]["PTS"]["landmarks"]["points"][3].pop(),
     "groups.PTS.landmarks", "different numbers of coordinates"),
    (lambda d: d["groups"]["PTS"]["landmarks"]["points"][3].__setitem__(0, "x"),
     "groups.PTS.landmarks", "not numbers"),
    (lambda d: d["groups"]["PTS"].pop("landmarks"), "groups.PTS.landmarks", "without"),
])
def test_bad_v3_files_are_refused_in_one_line(tmp_path, edit, field, words):
    data = v3(ibug_mm())
    edit(data)
    path = write(tmp_path / "bad.ljson", data)
    with pytest.raises(InputError) as exc:
        read_ibug68(path)
    one_line(exc, f"bad.ljson: field '{field}'", words)


def test_not_json_and_not_menpo_are_refused(tmp_path):
    (tmp_path / "x.ljson").write_text("{not json")
    with pytest.raises(InputError) as exc:
        read_ibug68(tmp_path / "x.ljson")
    one_line(exc, "x.ljson: field 'landmarks'", "not a JSON file")
    with pytest.raises(InputError) as exc:
        read_ibug68(write(tmp_path / "y.ljson", {"points": []}))
    one_line(exc, "y.ljson: field 'landmarks'", "not a menpo landmark file")
