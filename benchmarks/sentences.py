"""Visible speech of spoken sentences, per phone class, against issue 29's criteria.

Each of the Harvard sentences of lists 1 and 2 (IEEE 1969, public domain; none was tuned for)
is spoken by :func:`facemech.workflows.speak.speak`, the path of ``facemech speak``: eSpeak NG
at its default rate (175 words per minute; ``speak``'s own default is 160), the controls of
:func:`facemech.speech.coarticulation.controls_from_alignment`, the forward simulation on the
chosen face, planned for the face's dynamics as ``speak`` plans them by default
(:func:`facemech.speech.planning.plan_controls`; ``--no-plan``: the blend as it is,
``--plan-iterations N``); no movie, no blinks, gaze or head motion. Each phone is measured by
:func:`facemech.speech.visible_speech.measure_phones`.

Prints JSON: the settings; ``criteria`` (the issue's); ``summary``
(:func:`~facemech.speech.visible_speech.summarize`: per group the share passing, the median,
the worst phone, whether the criterion is met; the sentences' peak lower-lip speeds;
``incisor_speed``: the sentences' peak lower-incisor speeds, the jaw's, and how many exceed the
fastest jaw of issue 27's real recordings, 186 mm/s);
``incisor_opening``: the sentences' largest lower-incisor drops against a real jaw's 20 mm;
the summary's ``closure``, ``labiodental_front`` and ``round_opening`` rows: the bilabials'
seals, the lower lip's visible edge at the upper incisors with the lower incisors hidden, the
rounded openings' shape (the teeth shown measured with the jaw's poses); each sentence's
phones also go to stderr as a JSON line as it is done;
``classes`` (:func:`~facemech.speech.visible_speech.class_table`: lip gap and protrusion at
the phones' middles per articulatory class); ``sentences`` (per sentence: the duration, the
peak lower-lip and lower-incisor speeds, the wall time, the plan's simulations and kept
iteration);
``between_bilabials``: the stressed open vowels of
:data:`BETWEEN_BILABIALS` in a carrier phrase (the open vowels' criterion between two bilabials;
``--no-carrier`` leaves them out), with ``their_bilabials``, the bilabials of the same words (the
bilabials' criterion on them), and ``bilabial_with_the_words``: the bilabials' criterion on the
sentences' bilabials and those together. ``--phones`` adds every phone's row. Progress goes to
stderr (about 20-40 s a sentence on the 2-core machine).

``--preset FILE.json``: another physical preset (a preset file, e.g. the anatomical preset with
a ``step`` block; docs/formats.md).

``--held-out-2``: Harvard lists 5 and 6 (a second held-out set, first spoken after the
planner's gains of 2026-12-07 were set).

``--held-out``: Harvard lists 3 and 4 instead (20 sentences never used to set the planner's
targets, gains or bounds), the check of issue 29's "sentences that are not in the repository".

``python benchmarks/sentences.py [--voice en-gb] [--face default] [--rate 175]
[--sentences N] [--held-out | --held-out-2] [--no-carrier] [--phones] [--no-plan]
[--plan-iterations N] [--preset anatomical]``
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time

import numpy as np

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

#: Harvard sentences (IEEE 1969), lists 1 and 2
HARVARD = (
    # list 1
    "The birch canoe slid on the smooth planks.",
    "Glue the sheet to the dark blue background.",
    "It's easy to tell the depth of a well.",
    "These days a chicken leg is a rare dish.",
    "Rice is often served in round bowls.",
    "The juice of lemons makes fine punch.",
    "The box was thrown beside the parked truck.",
    "The hogs were fed chopped corn and garbage.",
    "Four hours of steady work faced us.",
    "A large size in stockings is hard to sell.",
    # list 2
    "The boy was there when the sun rose.",
    "A rod is used to catch pink salmon.",
    "The source of the huge river is the clear spring.",
    "Kick the ball straight and follow through.",
    "Help the woman get back to her feet.",
    "A pot of tea helps to pass the evening.",
    "Smoky fires lack flame and heat.",
    "The soft cushion broke the man's fall.",
    "The salt breeze came across from the sea.",
    "The girl at the booth sold fifty bonds.",
)
#: Harvard sentences (IEEE 1969), lists 3 and 4: a held-out set (``--held-out``), never used
#: to set a target, a gain or a bound
HELD_OUT = (
    # list 3
    "The small pup gnawed a hole in the sock.",
    "The fish twisted and turned on the bent hook.",
    "Press the pants and sew a button on the vest.",
    "The swan dive was far short of perfect.",
    "The beauty of the view stunned the young boy.",
    "Two blue fish swam in the tank.",
    "Her purse was full of useless trash.",
    "The colt reared and threw the tall rider.",
    "It snowed, rained, and hailed the same morning.",
    "Read verse out loud for pleasure.",
    # list 4
    "Hoist the load to your left shoulder.",
    "Take the winding path to reach the lake.",
    "Note closely the size of the gas tank.",
    "Wipe the grease off his dirty face.",
    "Mend the coat before you go out.",
    "The wrist was badly strained and hung limp.",
    "The stray cat gave birth to kittens.",
    "The young girl gave no clear response.",
    "The meal was cooked before the bell rang.",
    "What joy there is in living.",
)
#: Harvard sentences (IEEE 1969), lists 5 and 6: a second held-out set (``--held-out-2``), first
#: spoken on 2026-12-07 after the planner's gains of that day were set, never tuned on
HELD_OUT_2 = (
    # list 5
    "A king ruled the state in the early days.",
    "The ship was torn apart on the sharp reef.",
    "Sickness kept him home the third week.",
    "The wide road shimmered in the hot sun.",
    "The lazy cow lay in the cool grass.",
    "Lift the square stone over the fence.",
    "The rope will bind the seven books at once.",
    "Hop over the fence and plunge in.",
    "The friendly gang left the drug store.",
    "Mesh wire keeps chicks inside.",
    # list 6
    "The frosty air passed through the coat.",
    "The crooked maze failed to fool the mouse.",
    "Adding fast leaves the sum unclear.",
    "The show was a flop from the very start.",
    "A saw is a tool used for making boards.",
    "The wagon moved on well oiled wheels.",
    "March the soldiers past the next hill.",
    "A cup of sugar makes sweet fudge.",
    "Place a rosebush near the porch steps.",
    "Both lost their lives in the raging storm.",
)
#: words with an open vowel between two bilabials, none of which the Harvard lists above has,
#: each said in the carrier phrase "Say ___ again." (in en-us "o" is [ɑ])
BETWEEN_BILABIALS = ("bob", "pop", "mom", "bomb", "mop", "palm", "map", "pam")
CARRIER = "Say {} again."
#: eSpeak NG's default speaking rate (words per minute)
ESPEAK_DEFAULT_WPM = 175


def spoken_phones(text: str, *, voice: str = "en-us", rate_wpm: int = ESPEAK_DEFAULT_WPM,
                  face: str = "default", plan=True, preset: str = "anatomical"):
    """Speak ``text`` as ``facemech speak`` does (no movie, no liveliness) and measure it:
    (phone measures, peak lower-lip speed m/s, the utterance's duration s, the manifest's
    ``plan``, the lower incisor's peak speed m/s). ``plan``: as
    :func:`~facemech.workflows.speak.speak`'s."""
    from facemech.speech.alive import Liveliness
    from facemech.speech.mouth import incisor_drop
    from facemech.speech.visible_speech import (
        incisor_speed,
        measure_phones,
        peak_lower_lip_speed,
    )
    from facemech.workflows.speak import speak

    with tempfile.TemporaryDirectory() as tmp:
        sp = speak(tmp, text, voice=voice, rate_wpm=rate_wpm, face=face, plan=plan,
                   video=False, alive=Liveliness.off(), preset=preset)
    sim = sp.simulation
    phones = measure_phones(sp.alignment, sim.model, sim.time, sim.positions, voice=voice,
                            jaw_pose=sim.jaw_pose)
    jaw = float(incisor_speed(sim.time, sim.jaw_pose, sim.model).max())
    planned = {**sp.manifest["plan"],
               "incisor_opening_m": float(incisor_drop(sim.model, sim.jaw_pose).max())}
    return phones, peak_lower_lip_speed(sim.time, sim.positions, sim.model), \
        float(sp.alignment.duration), planned, jaw


def _jaw_row(peaks, real_mm_s: float) -> dict:
    """The utterances' peak lower-incisor speeds (m/s) in mm/s: min, median, max, and how many
    are faster than the fastest real jaw (``real_mm_s``)."""
    v = 1e3 * np.asarray(peaks, float)
    return {"n": int(v.size), "min_mm_s": round(float(v.min()), 1),
            "median_mm_s": round(float(np.median(v)), 1), "max_mm_s": round(float(v.max()), 1),
            "real_peak_mm_s": real_mm_s, "faster_than_real": int((v > real_mm_s).sum())}


#: mm, the farthest a real jaw drops the lower incisor in running speech (issue 53: <= 20 mm in
#: >= 90 % of sentences)
REAL_JAW_OPENING_MM = 20.0


def _opening_row(openings) -> dict:
    """The utterances' largest lower-incisor drops (m) in mm: min, median, max and the share
    within :data:`REAL_JAW_OPENING_MM`."""
    v = 1e3 * np.asarray(openings, float)
    return {"n": int(v.size), "min_mm": round(float(v.min()), 1),
            "median_mm": round(float(np.median(v)), 1), "max_mm": round(float(v.max()), 1),
            "share_within": round(float(np.mean(v <= REAL_JAW_OPENING_MM)), 3)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--voice", default="en-us")
    ap.add_argument("--face", default="default")
    ap.add_argument("--rate", type=int, default=ESPEAK_DEFAULT_WPM, help="words per minute")
    ap.add_argument("--sentences", type=int, default=len(HARVARD))
    ap.add_argument("--held-out", action="store_true",
                    help="Harvard lists 3 and 4 instead of 1 and 2 (never tuned on)")
    ap.add_argument("--held-out-2", action="store_true",
                    help="Harvard lists 5 and 6 instead (a second set never tuned on)")
    ap.add_argument("--no-carrier", action="store_true",
                    help="leave out the words with an open vowel between two bilabials")
    ap.add_argument("--phones", action="store_true", help="every phone's row")
    ap.add_argument("--no-plan", action="store_true", help="the dominance blend, not planned")
    ap.add_argument("--plan-iterations", type=int, default=None,
                    help="the planner's iterations (default: speak's)")
    ap.add_argument("--preset", default="anatomical", help="a preset name or a preset file")
    args = ap.parse_args(argv)
    plan = False if args.no_plan else (True if args.plan_iterations is None
                                        else args.plan_iterations)
    from facemech.speech.visible_speech import (
        CRITERIA,
        REAL_JAW_PEAK_MM_S,
        class_table,
        summarize,
    )

    rows, phones, speeds, jaws = [], [], [], []
    if args.held_out and args.held_out_2:
        ap.error("--held-out and --held-out-2 name different sets: give one")
    texts = (HELD_OUT if args.held_out else HELD_OUT_2 if args.held_out_2 else
             HARVARD)[: args.sentences]
    for k, text in enumerate(texts, 1):
        t0 = time.perf_counter()
        ph, peak, dur, planned, jaw = spoken_phones(text, voice=args.voice, rate_wpm=args.rate,
                                                    face=args.face, plan=plan,
                                                    preset=args.preset)
        wall = time.perf_counter() - t0
        phones += ph
        speeds.append(peak)
        jaws.append(jaw)
        rows.append({"text": text, "duration_s": round(dur, 3), "phones": len(ph),
                     "peak_lower_lip_speed_mm_s": round(1e3 * peak, 1),
                     "peak_incisor_speed_mm_s": round(1e3 * jaw, 1),
                     "incisor_opening_mm": round(1e3 * planned["incisor_opening_m"], 1),
                     "wall_s": round(wall, 1),
                     "plan_simulations": planned.get("simulations"),
                     "plan_kept_iteration": planned.get("kept_iteration")})
        print(f"[{k}/{len(texts)}] {wall:5.1f} s  peak {1e3 * peak:5.1f} mm/s  "
              f"incisor {1e3 * jaw:5.1f} mm/s  {text}", file=sys.stderr, flush=True)
        print(json.dumps({"text": text, "phones": [p.to_dict() for p in ph], **rows[-1]}),
              file=sys.stderr, flush=True)  # each sentence's rows as it is done
    out = {"voice": args.voice, "rate_wpm": args.rate, "face": args.face, "plan": plan,
           "sentences_set": "Harvard lists 3-4 (held out)" if args.held_out else
           "Harvard lists 5-6 (held out)" if args.held_out_2 else "Harvard lists 1-2",
           "preset": args.preset,
           "criteria": CRITERIA, "summary": summarize(phones, speeds),
           "classes": class_table(phones), "sentences": rows}
    out["summary"]["incisor_speed"] = _jaw_row(jaws, REAL_JAW_PEAK_MM_S)
    out["summary"]["incisor_opening"] = _opening_row([r["incisor_opening_mm"] / 1e3
                                                      for r in rows])
    if not args.no_carrier:
        between, flanking, word_jaws = [], [], []
        for k, word in enumerate(BETWEEN_BILABIALS, 1):
            ph, _, _, _, jaw = spoken_phones(CARRIER.format(word), voice=args.voice,
                                             rate_wpm=args.rate, face=args.face, plan=plan,
                                             preset=args.preset)
            word_jaws.append(jaw)
            between += [p for p in ph if p.between_bilabials]
            flanking += [p for p in ph if p.group == "bilabial"]
            print(f"[{k}/{len(BETWEEN_BILABIALS)}] {CARRIER.format(word)}", file=sys.stderr,
                  flush=True)
        out["between_bilabials"] = summarize(between)["open"]["between_bilabials"]
        out["between_bilabials"]["words"] = list(BETWEEN_BILABIALS)
        # the bilabials of the same words, beside those open vowels, and every bilabial said
        out["between_bilabials"]["their_bilabials"] = summarize(flanking)["bilabial"]
        out["between_bilabials"]["incisor_speed"] = _jaw_row(word_jaws, REAL_JAW_PEAK_MM_S)
        out["bilabial_with_the_words"] = summarize(phones + flanking)["bilabial"]
        if args.phones:
            out["between_bilabials"]["phones"] = [p.to_dict() for p in between + flanking]
    if args.phones:
        out["phones"] = [p.to_dict() for p in phones]
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
