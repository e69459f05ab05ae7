"""The packing drivers, written once over a shape's distance oracle and a backend's kernels.

- :mod:`.greedy`: ProtoSphere, the greedy (Apollonian) packing: ``nd.pack`` (faithful and fast
  modes) and ``nd.pack_sizes``, its size-distribution variant;
- :mod:`.sizes`: target distributions of radii (``nd.SizeDistribution``) and how far a packing is
  from one;
- :mod:`.collision`: spheres that *cover* a shape (``nd.cover``): collision spheres, sphere trees,
  robots' links.

A new driver is a package or module here; the scale-out of :mod:`ndpack.scale` runs any of them on
many parts or tiles.
"""
