"""The command line's options, as data: each option's help (:data:`HELP`), its names where
they are not ``--the-parameter`` (:data:`NAMES`), the input groups a command takes as one
parameter (:data:`GROUPS`; their options declared on their dataclasses) and the interval its
numbers must lie in (:data:`RANGES`, from the one table of :mod:`facemech.checks`), with
:func:`check_number`, which :mod:`facemech.cli` applies to every number a command is given
before it runs. Pure Python: importing it costs nothing."""

from __future__ import annotations

from .checks import RANGES as _RANGES
from .checks import check_number
from .inputs import Input, from_keys, inputs_of
from .inverse.options import FitOptions, InversionOptions
from .jaw.inputs import JawMarkers, JawSource
from .workflows import inputs as _groups

__all__ = ["GROUPS", "HELP", "NAMES", "RANGES", "check_number", "group_inputs", "help_for",
           "make_group"]

_HELP_TABLE = """
aa: anti-aliasing: samples per pixel and axis
as_json: print JSON
audio: WAV to mux in
background: '#rrggbb', 'r,g,b' or 'transparent' (PNG)
baseline: rest interval START,STOP (s)
builtin: refit the built-in targets
calibration: recording of maximal gestures
calibration_baseline: its rest interval START,STOP (s)
controls: speech, emg7, all, or listed groups (default: speech, or what the markers determine)
design: design table (.csv or .toml)
dt: Euler step of every evaluation, s (default: the preset's)
emg: raw EMG (CSV or C3D), 7 channels
eps: data precision, e.g. 0.5mm (default: noise)
face: face .npz, default, default-coarse or default-fine
figure: PNG of the controls (+-2 SE) and error
figures: with -o: PNGs
files: marker files, one per utterance
fit: scales: force, lips, stiffness, sphincter
fmt: obj or ply: one mesh per frame in the folder -o
frames: frames of the gesture sequence
front: marker in front, on the same plane
gestures: maximal gestures, each FILE:GROUPS, e.g. smile.c3d:ZYG,LAO,RIS
head: comma-separated head markers (at least 3)
integrator: euler, implicit or rosenbrock
k: independent markers (default: <= 10)
labels: name the markers
landmarks: landmark CSV name,x,y,z, or iBUG-68 .pts/.ljson/CSV
axes: the file's axes for facemech's x,y,z, e.g. --axes=x,z,-y (a z-up scan), --axes=-x,y,z
left: marker on the left
map_file: marker,node CSV (default: closest nodes)
max_gap: longest gap to fill, s
measured: measured markers (same names)
method: lsq (fast) or powell (the seeds')
name: model name
neutral: 'first' or a marker file: its first frame
noise: marker noise for the SEs, mm (or fit)
noise_mm: Gaussian marker noise, mm
origin: origin marker (default: --front)
out_units: unit of the output (default: the input's)
output: the output (file or folder)
peak: frame of a peak: a muscle group (e.g. OOS), jaw or motion
preset: anatomical, lucero1999, pitermann2001, calibrated or a preset .json
rate: rate, Hz (default: the frame rate)
reference: reference frame (default: first full)
report: write the per-frame residuals (JSON)
result: results file (.nc)
right: marker on the right
series: with --json: the per-frame mouth measures
size: frame size WIDTHxHEIGHT, pixels
source: input marker file
test: held-out utterances, e.g. 31-40
text: what to say (or --audio)
time: time of the frame, s
tissue: anatomical or uniform
title: page title
train: utterances to fit, e.g. 1-30
units: length unit if the file has none
utterances: utterances in the corpus
video: render the MP4
view: frontal, profile, three-quarter, mouth, frontal+profile
calibrate.max_evaluations: gesture sets simulated at most
calibrate.name: preset name (default: the file's)
calibrate.output: preset file (.json)
compare.a: results or marker file: the model
compare.b: results or marker file: the data
compare.markers: comma-separated (default: all shared)
demo.output: output folder
emg_process.output: activity CSV
experiment_lucero2008.frames: per utterance
experiment_lucero2008.k: markers of the basis
experiment_lucero2008.output: output folder
experiment_pitermann_crosstalker.output: JSON file of the table
experiment_pitermann_synthetic.method: lsq, powell or both
experiment_pitermann_synthetic.output: folder: summary.json, PNGs
export.blendshapes: arkit: ARKit's 52 blendshapes from the model's gestures, fitted weights
export.face: with --blendshapes: the result's face (default: the one it names)
export.output: file, or a folder with --format
export.units: unit of the output
face_build.output: the face model (.npz)
face_build.surface: OBJ (+ MTL, texture), PLY or STL
face_build.units: length unit of both files (mm, cm, m, um), or auto: from the face's size
face_export_default.output: folder for face.obj and landmarks.csv
face_from_photo.front: frontal photo of the face (JPEG, PNG)
face_from_photo.output: the talker (.npz)
face_from_photo.profile: profile photo on a plain background: depth of nose, lips, chin
face_from_photo.ipd: interpupillary distance, mm (default: adult norm 63.4, Dodgson 2004)
face_from_photo.distance: camera to face, m
face_info.face: face file or built-in face
invert.output: results file (.nc)
markers_convert.output: the output marker file (or TARGET)
markers_convert.target: or -o
markers_fill_gaps.output: the output marker file (.c3d, .trc or .csv)
markers_frame.output: the output marker file (.c3d, .trc or .csv)
markers_frame.reference: frame the axes are taken from
markers_head_correct.output: the output marker file (.c3d, .trc or .csv)
markers_resample.output: the output marker file (.c3d, .trc or .csv)
markers_trim.output: the output marker file (.c3d, .trc or .csv; a CSV keeps the roles)
plot.markers: comma-separated marker names
plot.output: PNG
regions.method: qrcp or strong
regions.output: output folder
render.output: MP4, or a folder for PNG frames
simulate.output: results file (.nc)
simulate.video: also render an MP4 (or PNG frames into a folder)
speak.output: output folder
still.markers: draw the model's markers
still.output: PNG or PDF
stimuli.output: output folder
view.markers: measured markers in the model's frame, drawn beside its own
view.output: HTML page
face_landmarks.surface: a scan: OBJ, PLY or STL, any orientation
face_landmarks.output: landmark CSV (name,x,y,z,confidence) and, beside it, a PNG
face_landmarks.units: length unit of the scan and the CSV
manifest: manifest of items (.csv or .toml)
batch.output: output folder: one folder per item, summary.csv
workers: local worker processes (default: one per core)
scheduler: a dask scheduler, tcp://HOST:8786 (instead of local workers)
threads: force-kernel threads (default: the cores available, or FACEMECH_THREADS; see docs)
subject.face: a built-in face, a face file (.npz), or a scan (OBJ/PLY/STL; --landmarks)
subject.markers: a recording (C3D, TRC, CSV) holding the face at rest
subject.output: the subject folder
frame: RIGHT,LEFT,FRONT markers of an anatomical frame (or 4 named as landmarks)
rest: START,STOP (s) of rest in --markers
warp: warp the face onto the rest markers (default: for built-in faces)
subject.chin_marker: a jaw marker for analyse: its drop gives the jaw
subject.jaw_second_marker: another jaw marker: rotation and glide
analyse.subject: a subject folder (facemech subject)
recording: a recording of the subject's markers (C3D, TRC, CSV), any rate
analyse.output: the results folder
tracker: mesh (MediaPipe's face mesh) or dlib (68 points)
lipread.size: the frames' WIDTHxHEIGHT, px
lipread.output: CSV of the series per frame (time, aperture, inner-lip distance)
"""
#: parameter -> help; ``command.parameter`` (the command function's name) overrides it there.
#: The options of an input group declare their own help (:data:`GROUPS`)
HELP: dict[str, str] = dict(line.split(": ", 1) for line in _HELP_TABLE.strip().splitlines())

#: parameter -> its option names, where they differ from ``--the-parameter``
NAMES: dict[str, tuple[str, ...]] = {
    "output": ("-o", "--output"), "as_json": ("--json",), "fmt": ("--format",),
    "noise_mm": ("--noise",), "map_file": ("--map",), "k": ("-k",),
    "aa": ("--aa",)}

#: input groups: options that a command takes as one parameter (so that no command has more
#: than 12), each an input group declared once (a dataclass of :mod:`facemech.inputs`, whose
#: fields give the options' names, types, defaults and help)
GROUPS: dict[str, type] = {
    "controls": _groups.Controls, "jaw_source": JawSource, "stepping": _groups.Stepping,
    "marker_file": _groups.MarkerFile, "model": _groups.PresetChoice, "jaw_markers": JawMarkers,
    "inversion": InversionOptions, "fit": FitOptions,
    "reader": _groups.MarkerReading, "bounds": _groups.Bounds,
    "analysis": _groups.Analysis, "preparation": _groups.Preparation,
    "speaking": _groups.Speaking, "recording": _groups.Recording, "alive": _groups.Alive,
}


def group_inputs(group: str) -> tuple[Input, ...]:
    """The options of the input group ``group`` of :data:`GROUPS` (:class:`~.inputs.Input`)."""
    return inputs_of(GROUPS[group])


def make_group(group: str, values: dict):
    """The input group ``group`` (its dataclass) made from a command's parameters (popped from
    ``values``)."""
    return from_keys(GROUPS[group], {i.key: values.pop(i.key) for i in group_inputs(group)})


#: parameter -> the interval its value must lie in, for the numbers that are options of a
#: command: the rows of the one table (:mod:`facemech.checks`) that the Python API checks too
RANGES: dict[str, str] = {k: v for k, v in _RANGES.items()
                          if k in HELP or any(h.endswith("." + k) for h in HELP)
                          or any(k == i.key for g in GROUPS for i in group_inputs(g))}


def help_for(command: str, parameter: str, spec=...) -> str | None:
    """The help of ``parameter`` in the command whose function is named ``command``: the
    command's own line, else the input's declared help (``spec``: the input, None for a plain
    parameter; not given: the first input group with that key), else the table's."""
    if spec is ...:
        spec = next((i for g in GROUPS for i in group_inputs(g) if i.key == parameter), None)
    return HELP.get(f"{command}.{parameter}") or (spec.help if spec else None) or HELP.get(
        parameter)
