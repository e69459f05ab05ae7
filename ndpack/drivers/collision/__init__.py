"""Spheres whose union covers a shape (collision spheres): the covering (:mod:`.covering`), sphere
trees (:mod:`.sphere_tree`), points on and in a shape (:mod:`.boundary`, :mod:`.inside_cells`), and a
robot's links from its URDF (:mod:`.robots`)."""
