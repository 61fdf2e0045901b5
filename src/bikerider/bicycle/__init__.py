"""Bicycle measurements: geometry, masses, centres of mass, pendulum reductions."""

from bikerider.bicycle.bodies import BODY_NAMES, OPTIONAL_BODY_NAMES, SEATING_NAMES, BicycleBodies

__all__ = ["BODY_NAMES", "OPTIONAL_BODY_NAMES", "SEATING_NAMES", "BicycleBodies"]
