"""Solvers: the explicit state, the step function, integrators, the jaw and forward simulation."""
