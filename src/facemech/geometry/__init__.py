"""Face geometry: the built-in generic face, surface and landmark files, the model builder.

- the data: :mod:`model` (the face model), :mod:`kinds` (its integer codes), :mod:`face_file`
  (its ``.npz`` file), :mod:`appearance` (a scan's look);
- the inputs: :mod:`generic` (the built-in face), :mod:`surface_io` (surface and landmark
  files), :mod:`anatomy` (muscle and marker sites), :mod:`tissue` (soft-tissue fields);
- the builder, :mod:`builder` (:func:`~.builder.build_face`, the built-in faces), and its steps:
  :mod:`options`, :mod:`mesh`, :mod:`mouth`, :mod:`layers`, :mod:`topology`, :mod:`jaw`,
  :mod:`warp`, :mod:`sites`, :mod:`muscle_sites`.
"""
