"""The fit per sensor and axis and the combinations of controls the markers measure, on
analytic cases: known offsets and scales give known RMS, correlation and range share; known step
responses give known combinations, standard errors and notes."""

import numpy as np
import pytest

from facemech.inverse import uncertainty as U
from facemech.inverse.combinations import determined_combinations, from_json, to_json
from facemech.inverse.determined import (
    full_activity_notes,
    identifiability_notes,
    regularised,
)
from facemech.inverse.sensor_fit import fit_from_json, fit_lines, fit_to_json, sensor_fit


def _sensors(frames=200):
    t = np.linspace(0.0, 1.0, frames)
    measured = np.zeros((frames, 2, 3))
    measured[:, 0, 1] = 0.004 * np.sin(2 * np.pi * 3 * t)  # ul y: +-4 mm
    measured[:, 0, 2] = 0.002 * np.cos(2 * np.pi * 2 * t)  # ul z
    measured[:, 1, 1] = 0.006 * np.sin(2 * np.pi * 1.5 * t)  # ll y
    measured[:, 1, 2] = 0.001 * t  # ll z: a ramp
    measured[:, :, 0] = 0.01  # x: constant (midsagittal, pinned)
    return measured


def test_scaled_and_offset_model_gives_known_rms_corr_and_range_share():
    measured = _sensors()
    model = measured.copy()
    model[:, 0, 1] = 0.5 * measured[:, 0, 1] + 0.001  # half the range, 1 mm up
    model[:, 0, 2] = -measured[:, 0, 2]  # mirrored: r = -1, full range
    model[:, 1, 1] = measured[:, 1, 1] + 0.002  # 2 mm offset only
    fits = {(f.sensor, f.axis): f for f in sensor_fit(model, measured, ["ul", "ll"])}
    assert set(fits) == {("ul", "y"), ("ul", "z"), ("ll", "y"), ("ll", "z")}  # no constant x
    d = -0.5 * measured[:, 0, 1] + 0.001
    assert fits["ul", "y"].rms_mm == pytest.approx(1e3 * np.sqrt(np.mean(d ** 2)), rel=1e-12)
    assert fits["ul", "y"].largest_mm == pytest.approx(1e3 * np.abs(d).max(), rel=1e-12)
    assert fits["ul", "y"].corr == pytest.approx(1.0, abs=1e-12)
    assert fits["ul", "y"].range_share == pytest.approx(0.5, rel=1e-12)
    assert fits["ul", "z"].corr == pytest.approx(-1.0, abs=1e-12)
    assert fits["ul", "z"].range_share == pytest.approx(1.0, rel=1e-12)
    assert fits["ll", "y"].rms_mm == pytest.approx(2.0, rel=1e-9)
    assert fits["ll", "y"].largest_mm == pytest.approx(2.0, rel=1e-9)
    assert fits["ll", "z"].rms_mm == pytest.approx(0.0, abs=1e-12)
    # an uncorrelated model: r near 0 (sin 3 Hz against cos 7 Hz over whole periods)
    t = np.linspace(0.0, 1.0, 200, endpoint=False)
    model[:, 0, 1] = 0.004 * np.cos(2 * np.pi * 7 * t)
    measured[:, 0, 1] = 0.004 * np.sin(2 * np.pi * 3 * t)
    assert abs(sensor_fit(model, measured, ["ul", "ll"])[0].corr) < 1e-9
    lines = fit_lines(sensor_fit(model, measured, ["ul", "ll"]))
    assert lines[1].startswith("ll: y RMS 2.00 mm, largest 2.00 mm, r 1.00, range 100 %")
    back = fit_from_json(fit_to_json(sensor_fit(model, measured, ["ul", "ll"])))
    assert back == sensor_fit(model, measured, ["ul", "ll"])


def test_missing_samples_are_left_out_of_a_sensors_fit():
    measured = _sensors()
    model = measured + 0.001
    measured[50:60, 0] = np.nan
    fits = sensor_fit(model, measured, ["ul", "ll"])
    assert fits[0].samples == 190 and fits[2].samples == 200
    assert all(f.rms_mm == pytest.approx(1.0) for f in fits)


#: two midsagittal sensors (rows: ul y, ul z, ll y, ll z), five controls: A lifts ul, B lowers
#: ll, C moves both forward, D lowers ul, E = 0.5 A + 0.5 B (no motion of its own)
NAMES = ("A", "B", "C", "D", "E")
S = np.array([[8.0, 0.0, 0.0, -3.0, 4.0],
              [0.0, 0.0, 5.0, 0.0, 0.0],
              [0.0, -10.0, 0.0, 0.0, -5.0],
              [0.0, 0.0, 2.0, 0.5, 0.0]])


def test_combinations_are_the_pivoted_rows_of_r_with_se_sigma_over_rkk():
    combos = determined_combinations(S, NAMES)
    assert len(combos) == 4  # rank 4: five controls, four measured combinations
    assert combos[0].lead == "B" and combos[0].motion_mm == pytest.approx(10.0)
    assert combos[0].weights["E"] == pytest.approx(0.5)  # E moves ll as half of B does
    assert combos[0].se(1.0) == pytest.approx(0.1)
    # the combinations reproduce the markers: S c is a function of the combinations only
    rng = np.random.default_rng(1)
    c1 = rng.uniform(0, 1, 5)
    null = np.linalg.svd(S)[2][-1]
    c2 = c1 + 0.1 * null  # same marker motion
    np.testing.assert_allclose(S @ c1, S @ c2, atol=1e-12)
    for c in combos:
        assert c.of(c1[None], NAMES)[0] == pytest.approx(c.of(c2[None], NAMES)[0], abs=1e-12)
    # SE at the noise floor within 0.1 iff |R_kk| >= 1 mm per unit (the control pick's rule)
    assert all(c.determined(0.05) == (c.motion_mm >= 1.0) for c in combos)
    assert [c.determined(0.6) for c in combos] == [c.motion_mm >= 6.0 for c in combos]
    assert from_json(to_json(combos)) == combos
    # the jaw first, whatever the pivot would choose
    assert determined_combinations(S, NAMES, first=("C",))[0].lead == "C"


def test_the_notes_name_combinations_and_regularised_controls_consistently():
    combos = determined_combinations(S, NAMES)
    seen = [False] * 5
    controls = np.full((10, 5), 0.2)
    note = identifiability_notes(combos, seen, controls, NAMES, 0.5)[0]
    assert note.startswith("determined by these markers: 4 combinations of the 5 controls")
    assert "B + 0.50 E: mean 0.30 (0.30 to 0.30), SE 0.05" in note
    assert "regularised (their values follow the regularisation, not the data): A, B, C, D, E" \
        in note
    assert regularised(combos, seen, NAMES)[0] == "E"  # in no combination as a lead
    assert identifiability_notes(combos, [True] * 5, controls, NAMES, 0.5) == []
    assert U.IDENTIFIABLE_SE == 0.1


def test_a_control_at_full_activity_in_more_than_a_tenth_of_the_frames_gets_a_note():
    c = np.zeros((100, 3))
    c[:43, 0] = 1.0
    c[:10, 1] = 0.995  # exactly 10 %: no note
    c[:, 2] = 0.98
    notes = full_activity_notes(c, ("MEN", "DLI", "OOS"))
    assert len(notes) == 1 and notes[0].startswith("MEN at full activity (>= 0.99) in 43 % of")
    assert "not a measurement" in notes[0]


def test_fewer_coordinates_than_controls_leave_no_control_identifiable_alone():
    # two coordinates, three controls: a null direction touches every control
    np.testing.assert_allclose(U.identifiability(np.array([[1.0, 0.0, 1.0],
                                                           [0.0, 1.0, 1.0]])), 0.0)
    np.testing.assert_allclose(U.identifiability(np.array([[3.0, 0.0], [0.0, 0.0]])), [3.0, 0.0])
    # but the markers still measure two combinations, each with its SE
    combos = determined_combinations(np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]]), "ABC")
    assert len(combos) == 2


def test_the_viewer_warns_of_regularised_muscles():
    import xarray as xr

    from facemech.viz.viewer import undetermined_muscles

    assert undetermined_muscles(xr.Dataset(attrs={"regularised": ""})) == ([], None)
    names, warning = undetermined_muscles(xr.Dataset(attrs={
        "regularised": "MEN,DLI,jaw", "combinations_determined": "DLI + 0.30 MEN"}))
    assert names == ["MEN", "DLI"]
    assert warning.startswith("not determined by the markers alone") and "MEN, DLI, jaw" in warning
    assert warning.endswith("the markers measure DLI + 0.30 MEN")
