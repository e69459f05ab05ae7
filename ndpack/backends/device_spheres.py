"""A device copy of the driver's growing sphere arrays, shared by the GPU backends.

The driver only appends spheres, so each call copies up only the spheres added since the last
one. Arrays that do not extend the ones copied (other spheres: another run, another tile's
obstacles; :func:`~ndpack.backends.sphere_index.extends`) start a fresh copy.
"""

from __future__ import annotations

import numpy as np

from .sphere_index import extends, owner


class DeviceSpheres:
    """Sphere centres (m, d) and radii (m,) mirrored on a device.

    Parameters
    ----------
    empty : callable
        ``empty(capacity, dim) -> (centers, radii)``: new device arrays.
    write : callable
        ``write(centers, radii, start, host_centers, host_radii)``: copy host rows into the
        device arrays from row ``start`` on.
    keep : callable
        ``keep(new_centers, new_radii, old_centers, old_radii, count)``: copy the first ``count``
        rows of the old device arrays into the new ones.
    view : callable
        ``view(array, count)``: the first ``count`` rows of a device array.
    """

    def __init__(self, empty, write, keep, view):
        self.empty, self.write, self.keep, self.view = empty, write, keep, view
        self.count = 0
        self.first = self.last = None
        self.buffer = None  # the owner of the host arrays mirrored (sphere_index.owner)
        self.centers = self.radii = None
        self.dim = None
        self._views = (None, None, None)  # (count, centers, radii): views cost tens of us in numba-cuda

    def sync(self, centers: np.ndarray, radii: np.ndarray):
        """Device views equal to ``centers`` (m, d) float64 and ``radii`` (m,) float64."""
        count, dim = centers.shape
        same_prefix = (self.centers is not None and dim == self.dim
                       and extends(centers, self.count, self.buffer, self.first, self.last))
        self.buffer = owner(centers)
        if not same_prefix:
            self.count = 0
        if not same_prefix or count > self.capacity:
            capacity = max(64, 2 * count)
            new_centers, new_radii = self.empty(capacity, dim)
            if self.count:
                self.keep(new_centers, new_radii, self.centers, self.radii, self.count)
            self.centers, self.radii, self.dim = new_centers, new_radii, dim
            self._views = (None, None, None)
        if count > self.count:
            self.write(self.centers, self.radii, self.count,
                       np.ascontiguousarray(centers[self.count :]), np.ascontiguousarray(radii[self.count :]))
            self.count = count
            self.first, self.last = centers[0].copy(), centers[count - 1].copy()
        if self._views[0] != count:
            self._views = (count, self.view(self.centers, count), self.view(self.radii, count))
        return self._views[1:]

    @property
    def capacity(self) -> int:
        return 0 if self.radii is None else self.radii.shape[0]
