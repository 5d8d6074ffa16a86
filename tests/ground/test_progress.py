"""Progress as plain log lines, with a heartbeat, when output is not a terminal."""

import io
import subprocess
import sys
import time

import pytest

from facemech.progress import HEARTBEAT_S, LogProgress, count_line, duration, staged


class FakeClock:
    def __init__(self, t=100.0):
        self.t = t

    def __call__(self):
        return self.t


def test_log_lines_and_heartbeat_with_a_fake_clock():
    clock, s = FakeClock(), io.StringIO()
    log = LogProgress("demo", every=5.0, heartbeat=6.0, stream=s, clock=clock)
    report = staged(log)
    expected = []
    for t, action, printed in [
        (105, lambda: log.beat(), None),  # 5 s of silence: not yet
        (106, lambda: log.beat(), "demo: still working (6 s)"),
        (107, lambda: report("simulate", 0, 10), None),  # a stage's first report
        (110, lambda: report("simulate", 3, 10), None),  # 3 s into the stage: too soon
        # 3 frames more in 2 s since the first items: the 4 left take 2.7 s at that rate
        (112, lambda: report("simulate", 6, 10), "simulate: frame 6/10, 5.0 s elapsed, "
                                                  "about 3 s left"),
        (117, lambda: log.beat(), None),  # 5 s since the last line
        # the heartbeat repeats the count, the rate from the time since: 8 s / 3 frames * 4
        (118, lambda: log.beat(), "simulate: frame 6/10, 11.0 s elapsed, about 11 s left"),
        (119, lambda: report("simulate", 10, 10), "simulate: frame 10/10, 12.0 s elapsed"),
        (125, lambda: log.beat(), "demo: still working (25 s)"),  # no stage under way
    ]:
        clock.t = t
        action()
        if printed:
            expected.append(f"facemech: {printed}")
        assert s.getvalue().splitlines() == expected, t


def test_invert_counts_frames_with_the_time_left_when_piped():
    """invert's per-frame calls (done, total) under its stage "invert (lsq)": a count and an
    estimate on every line once frames come, the heartbeat's too; the estimate leaves out the
    time before the first frame (numba compiling); before it, the elapsed time only."""
    clock, s = FakeClock(0.0), io.StringIO()
    log = LogProgress("invert", every=5.0, heartbeat=6.0, stream=s, clock=clock)
    report = staged(log)
    for t, action in [(1.0, lambda: report("invert (lsq)", 0, 116)), (7.0, log.beat),
                      (7.5, lambda: report("invert (lsq)", 1, 116)),
                      (11.4, lambda: report("invert (lsq)", 40, 116)),
                      (12.5, lambda: report("invert (lsq)", 45, 116)),  # 44 frames in 5 s
                      (18.5, log.beat)]:  # 6 s silent: 44 frames in 11 s, 71 left
        clock.t = t
        action()
    assert s.getvalue().splitlines() == [
        "facemech: invert (lsq): still working (6 s)",
        "facemech: invert (lsq): frame 1/116, 6.5 s elapsed",
        "facemech: invert (lsq): frame 45/116, 11.5 s elapsed, about 8 s left",
        "facemech: invert (lsq): frame 45/116, 17.5 s elapsed, about 18 s left"]


def test_count_line_and_duration():
    assert count_line("render", 1, 4, 0.5, 1.5) == (
        "render: frame 1/4, 0.5 s elapsed, about 2 s left")
    assert count_line("fit", 3, None, 2.0, 1.0) == "fit: 3, 2.0 s elapsed"  # no total
    assert count_line("plan", 2, 9, 10.0, 35.0) == (
        "plan: iteration 2/9, 10.0 s elapsed, about 35 s left")
    assert count_line("fit", 3, 3, 2.0, 0.0) == "fit: 3/3, 2.0 s elapsed"  # complete
    assert count_line("build", 1, 10, 100.0, 900.0) == (
        "build: 1/10, 100.0 s elapsed, about 15 min 00 s left")
    assert [duration(x) for x in (0.4, 7.4, 59.4, 125.0)] == ["<1 s", "7 s", "59 s", "2 min 05 s"]


def test_heartbeat_thread_prints_while_silent_and_stops_cleanly():
    s = io.StringIO()
    log = LogProgress("render", heartbeat=0.05, stream=s)
    with log:
        with log:  # entered again (a stage inside the command): still one thread
            thread = log._thread
            time.sleep(0.5)
        assert log._thread is thread and thread.is_alive()
    assert log._thread is None and not thread.is_alive()
    lines = s.getvalue().splitlines()
    assert len(lines) >= 4
    assert all(ln.startswith("facemech: render: still working (") for ln in lines)
    time.sleep(0.2)
    assert s.getvalue().splitlines() == lines  # nothing after the end


@pytest.mark.slow
def test_demo_under_a_pipe_keeps_printing_lines(tmp_path):
    """``facemech demo`` with stderr piped: log lines come while it works (the stages' counts,
    the heartbeat's when a stage is silent), and the last one soon before the exit.

    The heartbeat's timing itself is tested with a fake clock above. Here the clock of a real
    run decides nothing but a loose bound (issue 32): on a machine loaded several times over,
    the interpreter's start (before any facemech code runs, so not timed) and a heartbeat that
    waits for numba's compiler to let go of the GIL take longer than on a quiet one; no silence
    between two lines, or before the exit, may exceed three heartbeats."""
    start = time.monotonic()
    stamps, lines = [], []
    with subprocess.Popen([sys.executable, "-m", "facemech.cli", "demo", "-o",
                           str(tmp_path / "d"), "--no-video"], stdout=subprocess.DEVNULL,
                          stderr=subprocess.PIPE, text=True, bufsize=1) as proc:
        for line in iter(proc.stderr.readline, ""):
            stamps.append(time.monotonic())
            lines.append(line.rstrip())
        assert proc.wait() == 0, "\n".join(lines)
    stamps.append(time.monotonic())
    assert stamps[0] > start and len(lines) >= 2, lines
    gaps = [b - a for a, b in zip(stamps, stamps[1:], strict=False)]
    assert max(gaps) <= 3 * HEARTBEAT_S, list(zip(gaps, lines, strict=False))
    assert all(ln.startswith("facemech: ") for ln in lines), lines
    assert any(ln.startswith("facemech: simulate: frame 155/155, ") for ln in lines), lines
    assert (tmp_path / "d" / "result.nc").is_file()
    assert (tmp_path / "d" / "view.html").is_file()  # the demo writes its viewer page too
