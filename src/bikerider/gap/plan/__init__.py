"""The next experiment: the rivals of the selection, the runs that would tell them apart, ranked,
and the speed sweeps."""
