"""Errors raised by ndpack.

Every problem with user input raises a subclass of :class:`NdpackError`, with a message that
says what was wrong and what to do. The subclasses also derive from the matching built-in
exception (``ValueError``, ``TypeError``), so generic handlers keep working.
"""


class NdpackError(Exception):
    """Base class of every error ndpack raises on purpose."""


class ShapeError(NdpackError, ValueError):
    """A shape is ill-defined: wrong parameters, no interior, unbounded where bounds are needed."""


class DimensionError(ShapeError):
    """Points or shapes of different dimensions were combined."""


class BoundsError(ShapeError):
    """A shape's bounds are missing, infinite, or do not enclose the shape."""


class OracleError(NdpackError, ValueError):
    """A distance oracle returned something unusable (NaN, wrong shape)."""


class ParameterError(NdpackError, ValueError):
    """A packing parameter is impossible (negative count, zero iterations, ...)."""


class BackendError(NdpackError, RuntimeError):
    """A backend is unknown, not installed, or cannot run here."""


class KernelError(NdpackError, TypeError):
    """A shape or plug-in cannot be compiled to a scalar kernel for a compiled backend."""


class MeshWarning(UserWarning):
    """A mesh was repaired in a way that changes its shape (its holes capped), or a sign method that
    can be wrong was asked for."""


class GridWarning(UserWarning):
    """The shape is thinner than the packing grid's cells: the first points inside it were found
    by a search, and spheres may come out well below the largest that fit (pass a finer ``grid=``)."""


#: How an :class:`InvalidPackingError`'s message ends when it keeps the packing.
KEPT_IN_ERROR = "The packing as made is in error.packing."


class InvalidPackingError(NdpackError, RuntimeError):
    """A packing failed the driver's final check: ``on_invalid="raise"`` asked not to repair it,
    or nothing could (a volume the spheres exceed).

    Attributes
    ----------
    packing : Packing or None
        The packing as made, so that a long run is not lost with the error.
    """

    def __init__(self, message: str, packing=None):
        super().__init__(message)
        self.packing = packing


class RepairWarning(RuntimeWarning):
    """A packing failed the final float64 check and was repaired (spheres shrunk or dropped).

    The repair is recorded in :attr:`ndpack.Packing.repair`. The test suite turns this warning
    into an error, so a backend or oracle that needs repairs cannot pass unseen.
    """
