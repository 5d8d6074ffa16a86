"""Dynamic inversion (Pitermann & Munhall 2001): muscle activity from marker motion."""
