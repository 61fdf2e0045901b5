"""The physics on trial: the registry of candidate effects, the nominal model input, and the effect
model that adds a candidate to the benchmark bicycle."""
