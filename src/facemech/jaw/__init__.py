"""The jaw's drives from recordings, for every command: what a command is given
(:mod:`.inputs`: a file of angles or of jaw markers for ``simulate``, the jaw's markers inside
an inverted recording for ``invert``) and the one drive that turns the jaw's markers into a
series of angles (a skin chin marker) or sagittal poses (two mandible markers, or a
lower-incisor sensor with or without a molar pellet): :func:`.drive.jaw_drive`.
The jaw's kinematics and the solvers that move it stay in :mod:`facemech.solvers`."""
