"""ndpack: fill any shape, in any dimension, with non-overlapping spheres.

Give it a distance oracle (signed distance, negative inside) and it packs spheres greedily,
largest first, with the ProtoSphere algorithm::

    import ndpack as nd
    part = nd.Box([0, 0, 0], [1, 1, 1]) - nd.Ball([1, 1, 1], 0.6)
    packing = nd.pack(part, n=1000, seed=0)
    packing.fill, packing.verify()

Everything public is re-exported here; the rest is internal.
"""

from .errors import (
    BackendError,
    KernelError,
    GridWarning,
    MeshWarning,
    BoundsError,
    DimensionError,
    InvalidPackingError,
    NdpackError,
    OracleError,
    ParameterError,
    RepairWarning,
    ShapeError,
)
from .drivers.collision.covering import CoverReport, Covering, check_covering, cover
from .scale.many import ManyResult, pack_many
from .oracle import Oracle, Volume, ball_volume
from .packing import Packing, RoundStats
from .drivers.greedy.protosphere import Round, pack, pack_sizes
from .drivers.dense import pack_dense
from .geometry.rotation import rotation
from .drivers.sizes import SizeDistribution, SizeReport
from .scale.tiled import pack_tiled
from .shapes import *  # noqa: F403  (the shape classes, listed in shapes.__all__)
from .shapes import __all__ as _shape_names
from .verify import Verification, verify
from . import io, pictures  # noqa: F401  (they register Packing.save, Packing.load and Packing.plot)

__version__ = "0.1.0"

__all__ = [
    "BackendError", "BoundsError", "KernelError", "DimensionError", "GridWarning", "InvalidPackingError", "MeshWarning",
    "NdpackError", "OracleError", "Oracle",
    "Packing", "ParameterError", "RepairWarning", "Round", "RoundStats", "ShapeError", "Verification", "Volume",
    "ball_volume", "check_covering", "cover", "Covering", "CoverReport", "ManyResult", "pack", "pack_many",
    "pack_tiled", "pack_sizes", "pack_dense", "SizeDistribution",
    "SizeReport", "rotation", "verify", *_shape_names,
]
