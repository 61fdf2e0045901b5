"""Fits to measured signals: damped oscillations (pendulum periods, bicycle modes)."""

PERIOD_TRIAL_TOLERANCE = 0.01
"""Repeated trials of one period must lie within this fraction of their median.

Random timing error shows up as scatter well inside 1 %; a trial further off is a trial of another
orientation or body, or a slipping clamp, and is reported as an error rather than averaged in.
"""
