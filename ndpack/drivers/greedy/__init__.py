"""ProtoSphere's greedy packing: the run and its state (:mod:`.protosphere`), the round strategies
(:mod:`.rounds`), and which of a round's candidates meet (:mod:`.conflicts`)."""
