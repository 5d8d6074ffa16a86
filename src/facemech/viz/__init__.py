"""Pictures: a CPU rasteriser for the shaded skin, movies and kinematic plots (imported lazily)."""
