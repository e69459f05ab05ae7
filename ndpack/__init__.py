"""ndpack: fill any shape, in any dimension, with non-overlapping spheres."""
