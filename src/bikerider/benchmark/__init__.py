"""The benchmark parameters of Meijaard et al. (2007) and the linear Whipple model they give."""

from bikerider.benchmark.model import CriticalSpeeds, ModalEigenvalues, WhippleModel
from bikerider.benchmark.parameters import BENCHMARK_NAMES, BenchmarkParameters

__all__ = ["BENCHMARK_NAMES", "BenchmarkParameters", "CriticalSpeeds", "ModalEigenvalues", "WhippleModel"]
