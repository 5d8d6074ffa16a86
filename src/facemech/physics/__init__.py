"""Pure numerical kernels of the face model: springs, muscles, prisms, and their assembly."""
