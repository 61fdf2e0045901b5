"""bikerider: physical properties of a bicycle and its seated rider, the linear Whipple model they
give, and where real bicycles depart from it.

The method is that of Moore, Hubbard, Kooijman and Schwab (2009), "A method for estimating physical
properties of a combined bicycle and rider"; the model is the benchmark of Meijaard et al. (2007).

Layout
------
``bikerider.bicycle``   bicycle measurements and pendulum reductions
``bikerider.rider``     the rider model (grid points, closures, segments)
``bikerider.benchmark`` the 25 benchmark parameters and the Whipple model
``bikerider.estimate``  the whole pipeline, measurements to model
``bikerider.io``        input files (TOML, BicycleParameters text files)
``bikerider.cli``       the ``bikerider`` command line
``bikerider.generated`` NumPy functions generated from the SymPy derivations in ``derive/``
"""
__version__ = "0.1.0"
