"""Fitting a candidate to the data: the fit problem, the eigenvalue predictions, the indirect
(record) fits, the time-domain fits and the low-rank tests."""
