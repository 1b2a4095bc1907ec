"""Optimisation problems: the `Problem` base class (studies live in their own modules)."""

from legcore.problems.base import Problem, constraint_violation

__all__ = ["Problem", "constraint_violation"]
