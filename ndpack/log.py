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


def notice(message: str) -> None:
    """Tell the user ``message`` (INFO on the ``"ndpack"`` logger; see the module docstring)."""
    if logger.level == logging.NOTSET and not logger.handlers and not logging.getLogger().handlers:
        # Nobody configured logging: show notices, as a command-line tool would.
        logger.setLevel(logging.INFO)
        logger.addHandler(_AboveProgressBars())
        logger.propagate = False
    logger.info(message)
