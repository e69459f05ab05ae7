"""Geometry that everything may use, with no shape in it: periodic domains and their images
(:mod:`.period`), rotation matrices in any dimension (:mod:`.rotation`), and points against a union
of balls (:mod:`.ball_union`)."""
