"""The version of cracklab, readable by every layer (the package root imports everything)."""

__version__ = "0.1.0"
