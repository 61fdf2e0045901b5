"""The diagnosis: where the model misses, whether a candidate explains it, which one, and the
selection."""
