"""Errors with one clear line for the user; the CLI prints them without a traceback."""


class FlexsymError(Exception):
    exit_code = 1


class SpecError(FlexsymError):
    """A malformed variant, mode set, scene or parameter."""

    exit_code = 2


class ToolchainError(FlexsymError):
    """Missing compiler/cmake, or a failed build: the machine, not the input (exit 5)."""

    exit_code = 5


class OutputError(FlexsymError):
    """An output could not be written (no space left on device, an I/O error): the machine, not
    the input, as for ToolchainError (exit 5). Nothing is left half-written (core/files.py)."""

    exit_code = 5


class SimulationError(FlexsymError):
    """The integrator stopped: divergence, Newton failure, instability."""

    exit_code = 3

    def __init__(self, message: str, result=None):
        super().__init__(message)
        self.result = result
