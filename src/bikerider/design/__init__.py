"""Design-space exploration at scale: stability maps over millions of bicycles.

A design space is a grid or a random sample of designs over named parameters of a base bicycle
(benchmark parameters, or raw measurements through the whole estimate); a run evaluates every
design - validity, every self-stable speed interval, weave and capsize speeds, stability at the
speeds of a map, weave frequency and damping at chosen speeds - chunk by chunk into a Zarr store,
resumably, on this machine (every core, through fused C kernels emitted by ``derive/kernels.py``)
or on a Dask cluster.  See ``docs/design_space.md``.

==============================================  ================================================
:func:`grid`, :func:`random_designs`,           design spaces (:mod:`bikerider.design.space`)
:func:`monte_carlo`
:func:`explore`                                 run one into a store (:mod:`.run`, :mod:`.store`,
                                                :mod:`.distributed`)
:func:`open_store`                              read a run's results
:mod:`bikerider.design.summary`               ``summarize``, ``design_slice``,
                                                ``closest_to_weave_speed``
==============================================  ================================================

The store needs the extra ``bikerider[design]`` (Zarr), a Dask run ``bikerider[distributed]``.
"""

from bikerider.design.run import explore
from bikerider.design.space import DesignSpace, grid, monte_carlo, random_designs
from bikerider.design.store import DesignStore, open_store

__all__ = ["DesignSpace", "DesignStore", "explore", "grid", "monte_carlo", "open_store", "random_designs"]
