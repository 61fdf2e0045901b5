"""The sim-to-real gap: where a bicycle model departs from measurements, and which unmodelled effect
explains it (``bikerider gap``; docs/gap.md)."""
