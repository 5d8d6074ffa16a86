"""Library workflows: what each ``facemech`` command does, as functions usable from Python.

Each module holds the workflows of one concept (faces, EMG, markers, simulation, pictures); a
command of :mod:`facemech.cli` parses its options, calls one of these and prints the result.
Inputs are paths and explicit parameters; outputs are written atomically and returned as data.
Long workflows take a staged ``progress(stage, done, total)`` callback
(:data:`facemech.progress.StagedProgress`).
"""
