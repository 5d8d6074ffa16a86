"""Analyses: independent kinematic regions (Lucero & Munhall 2008) and their embedded corpus."""
