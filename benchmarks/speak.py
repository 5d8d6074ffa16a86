"""How long ``facemech speak`` takes for a sentence with its 720p movie, beside its parts
(issue 29: a 3-s sentence with its 720p movie in 30 s or less on the 2-core machine).

Prints JSON: the utterance's duration, the whole call's wall time, and each stage's (synthesis,
simulation, rendering, from the first to the last progress report of the stage; the rest is
writing, describing and the face's blinks, gaze and head motion).
``python benchmarks/speak.py [--text "..."] [--size 1280x720] [--view frontal]``.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time

#: a Harvard sentence (IEEE 1969, list 1), about 3 s at eSpeak's default rate
TEXT = "The birch canoe slid on the smooth planks."


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--text", default=TEXT)
    ap.add_argument("--size", default="1280x720")
    ap.add_argument("--view", default="frontal")
    args = ap.parse_args(argv)
    from facemech.workflows.pictures import render_options
    from facemech.workflows.speak import speak

    stages: dict[str, list[float]] = {}

    def progress(stage: str, done: int, total: int) -> None:
        now = time.perf_counter()
        span = stages.setdefault(stage, [now, now])
        span[1] = now

    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        res = speak(tmp, args.text, video=render_options(view=args.view, size=args.size),
                    progress=progress)
        wall = time.perf_counter() - t0
    out = {"text": args.text, "size": args.size, "view": args.view,
           "utterance_s": round(float(res.alignment.duration), 3),
           "frames": int(len(res.dataset["time"])), "wall_s": round(wall, 2),
           "plan_simulations": res.manifest["plan"].get("simulations"),
           "stages_s": {k: round(b - a, 2) for k, (a, b) in stages.items()}}
    out["rest_s"] = round(wall - sum(out["stages_s"].values()), 2)
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
