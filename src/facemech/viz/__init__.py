"""Pictures: a CPU rasteriser for the shaded skin, movies, kinematic plots and an interactive
HTML viewer (imported lazily)."""
