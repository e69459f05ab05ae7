"""ndpack's notices to the user: the ``"ndpack"`` logger.

Notices (a first-use compile, for example) are logged at INFO on the ``"ndpack"`` logger. Where
the program has not set up logging, they go to standard error as ``ndpack: ...`` lines, above a
progress bar if one is showing. To silence them::

    import logging
    logging.getLogger("ndpack").setLevel(logging.WARNING)
"""

from __future__ import annotations

import logging
import sys

logger = logging.getLogger("ndpack")


class _AboveProgressBars(logging.Handler):
    """Writes through ``tqdm.write``, so that a line does not break a progress bar."""

    def emit(self, record):
        try:
            from tqdm import tqdm

            tqdm.write(f"ndpack: {self.format(record)}", file=sys.stderr)
        except Exception:  # noqa: BLE001 - logging must never raise
            self.handleError(record)


def _shown() -> logging.Logger:
    """The logger, set to show notices where nobody configured logging (as a command-line tool would)."""
    if logger.level == logging.NOTSET and not logger.handlers and not logging.getLogger().handlers:
        logger.setLevel(logging.INFO)
        logger.addHandler(_AboveProgressBars())
        logger.propagate = False
    return logger


def notice(message: str) -> None:
    """Tell the user ``message`` (INFO on the ``"ndpack"`` logger; see the module docstring)."""
    _shown().info(message)


def warn(message: str) -> None:
    """Warn the user in one line, ``message`` (WARNING on the ``"ndpack"`` logger): for what ndpack
    declined to do but worked around (a cache folder refused), where a Python warning would be
    shown once per place in the code rather than once per process."""
    _shown().warning(message)


#: Set by ``ndpack.kernels.compile``, a layer above this one, when it is imported: says the first
#: compile of ndpack's own Numba functions as it says that of its generated kernels.
own_compile_hook = None


def numba_functions(module: str, what: str, typical: float) -> None:
    """Say the first compile on this machine of the Numba functions of ndpack's ``module``, which
    compile next, as ``what``, about ``typical`` seconds until the machine has timed them
    (through ``ndpack.kernels.compile``, where it is loaded; else nothing is said)."""
    if own_compile_hook is not None:
        own_compile_hook(module, what, typical)
