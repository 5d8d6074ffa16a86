"""Issue 31: no child process (ffmpeg, the C3D reader) reads the caller's standard input, so
``facemech`` can run inside a shell ``while read`` loop without eating the next line."""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import facemech

SENTENCES = ["Who knew you", "Move so soon", "We see a bee"]


def _words_in_alignment(path: Path) -> list[str]:
    lines = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
    return [r["label"] for r in csv.DictReader(lines) if r["tier"] == "words"]


@pytest.mark.slow
def test_speak_in_a_shell_loop_keeps_every_word(tmp_path):
    pytest.importorskip("imageio_ffmpeg")
    pytest.importorskip("espeakng_loader")
    (tmp_path / "sentences.txt").write_text("\n".join(SENTENCES) + "\n")
    env = dict(os.environ, PYTHONPATH=str(Path(facemech.__file__).parents[1]),
               FACEMECH_THREADS="1", OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    # the movie is what calls ffmpeg to mux the audio: keep it, but tiny
    script = ('i=0; while read s; do i=$((i+1)); '
              f'"{sys.executable}" -m facemech speak "$s" -o "out$i" --size 32x24 --aa 1 '
              '--view frontal --no-plan || exit 1; done < sentences.txt')
    run = subprocess.run(["bash", "-c", script], cwd=tmp_path, env=env, capture_output=True,
                         text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    for k, sentence in enumerate(SENTENCES, start=1):
        out = tmp_path / f"out{k}"
        assert (out / "movie.mp4").is_file()
        manifest = json.loads((out / "manifest.json").read_text())
        assert manifest["text"] == sentence
        expected = [w.lower() for w in sentence.split()]
        assert [w.lower() for w in manifest["alignment"]["words"]] == expected
        assert [w.lower() for w in _words_in_alignment(out / "alignment.csv")] == expected


def test_ffmpeg_muxing_leaves_the_callers_input_alone(tmp_path):
    """A mux long enough for ffmpeg to poll its keyboard (a 20-s movie): without -nostdin it
    reads a byte of the loop's next line (measured: 'abcdefgh' came back as 'bcdefgh')."""
    imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg")
    exe = imageio_ffmpeg.get_ffmpeg_exe()
    for args in (["-f", "lavfi", "-i", "testsrc=size=320x180:rate=60", "-t", "20", "-c:v",
                  "libx264", "-preset", "ultrafast", "v.mp4"],
                 ["-f", "lavfi", "-i", "sine=d=20", "a.wav"]):
        subprocess.run([exe, "-nostdin", "-y", "-loglevel", "error", *args], cwd=tmp_path,
                       check=True, stdin=subprocess.DEVNULL, timeout=120)
    lines = ["abcdefgh", "ijklmnop", "qrstuvwx"]
    (tmp_path / "lines.txt").write_text("\n".join(lines) + "\n")
    mux = ("import shutil, sys; from pathlib import Path; from facemech.viz.movie import _mux; "
           "v = Path(sys.argv[1]); shutil.copy('v.mp4', v); _mux(sys.argv[2], v, 'a.wav')")
    script = (f'i=0; while read s; do i=$((i+1)); "{sys.executable}" -c "{mux}" m$i.mp4 '
              f'"{exe}" || exit 1; echo "$s" >> got.txt; done < lines.txt')
    env = dict(os.environ, PYTHONPATH=str(Path(facemech.__file__).parents[1]))
    run = subprocess.run(["bash", "-c", script], cwd=tmp_path, env=env, capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    assert (tmp_path / "got.txt").read_text().splitlines() == lines
    assert all((tmp_path / f"m{k}.mp4").stat().st_size > 0 for k in (1, 2, 3))
