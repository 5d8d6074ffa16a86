"""The demo as a workflow: :func:`facemech.demo.run_demo` and the report the command prints."""

from __future__ import annotations

from pathlib import Path

from ..progress import StagedProgress
from .outcome import Written


def summary_text(s, output: str | Path) -> str:
    """Lines on a :class:`facemech.demo.DemoSummary`: frames and rate, simulation time and
    real-time factor, the largest lip displacement (mm), total wall time, the files written
    into ``output``."""
    output = Path(output)
    lines = [f"facemech demo -> {output}/",
             f"  frames: {s.frames} ({s.simulated_seconds:.2f} s at "
             f"{s.frames / s.simulated_seconds:g} Hz)",
             f"  simulation: {s.simulation_seconds:.1f} s wall, real-time factor "
             f"{s.real_time_factor:.2f} ({s.integrator})",
             f"  largest lip displacement: {s.largest_lip_displacement_mm:.2f} mm",
             f"  total wall time: {s.wall_seconds:.1f} s"]
    return "\n".join(lines + [f"  {k}: {output / v}" for k, v in s.output.items()])


def run(output: str | Path, *, integrator: str | None = None, video: bool = True,
        preset: str = "anatomical", render=None,
        progress: StagedProgress | None = None) -> Written:
    """Run the demo (:func:`facemech.demo.run_demo`) into the folder ``output``.

    Returns
    -------
    Written : ``data`` the :class:`facemech.demo.DemoSummary`, its line :func:`summary_text`
    """
    from ..atomic import check_output
    from ..demo import run_demo

    check_output(output, [preset if Path(str(preset)).suffix else None], folder=True,
                 field="-o")
    s = run_demo(output, integrator=integrator, video=video, preset=preset, progress=progress,
                 render=render)
    return Written(Path(output), s, summary_text(s, output))
