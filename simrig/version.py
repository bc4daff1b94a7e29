"""The package version and distribution name (records layer: anything may read it)."""

__version__ = "0.1.0"
DISTRIBUTION = "simrig-mot"
"""The name to ``pip install`` (the import name and the command are ``simrig``; PyPI's ``simrig`` is another
project's)."""
