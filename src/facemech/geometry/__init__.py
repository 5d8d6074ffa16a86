"""Face geometry: the built-in generic face, surface and landmark files, the model builder."""
