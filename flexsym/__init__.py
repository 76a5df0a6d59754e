"""flexsym: symbolic code generation for flexible multibody dynamics (floating frame of reference)."""

__version__ = "0.1.0"
