"""Readers of input files: the project's TOML, BicycleParameters ``name = value+/-sigma`` files."""
