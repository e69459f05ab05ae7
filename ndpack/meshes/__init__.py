"""Triangle meshes: a bounding-volume hierarchy, its kernels, and the surface checks behind the mesh oracle."""
