"""Symbolic derivations of bikerider, and the code generator that emits them as NumPy.

Run ``python -m derive`` (or ``make derive``) to regenerate ``generated/``.
Nothing here is imported at run time: the runtime in ``src/bikerider`` only imports
what this package writes into ``generated/``.
"""
