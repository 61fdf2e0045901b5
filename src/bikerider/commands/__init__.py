"""Subcommands of the ``bikerider`` command line, one module each."""
