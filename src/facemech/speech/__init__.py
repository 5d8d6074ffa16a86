"""Visible speech: text or a phoneme alignment to muscle activity and a jaw, and stimuli."""
