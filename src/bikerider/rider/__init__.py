"""The rider of Moore et al. (2009): 14 body measurements, a seated skeleton, mass properties."""

from bikerider.rider.measurements import DEFAULT_MASS_FRACTIONS, RIDER_NAMES, RiderMeasurements
from bikerider.rider.model import RiderModel, seat_rider

__all__ = ["DEFAULT_MASS_FRACTIONS", "RIDER_NAMES", "RiderMeasurements", "RiderModel", "seat_rider"]
