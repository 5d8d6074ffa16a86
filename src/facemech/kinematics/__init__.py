"""Marker kinematics: head-motion correction, face frames, gaps, resampling, mapping to nodes."""
