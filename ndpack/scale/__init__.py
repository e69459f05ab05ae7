"""Beyond one packing in one process: many parts at once (:mod:`.many`), one domain in tiles
(:mod:`.tiled`), and where their tasks run (:mod:`.workers`: this process, a local pool, Dask)."""
