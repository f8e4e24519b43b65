"""Training and the live puppet: from a performer's ten tracked values to three drawings per part.

* ``features``    — scale-free eye (k = 4) and mouth (k = 3) features relative to the neutral face
* ``session``     — a performer's training pairs (drawing ↔ frame) for one art set, JSON + PNG
* ``diagnostics`` — leave-one-out errors, hull coverage of the reference clip, what to add next
* ``filters``     — temporal filters of the parameter stream (paper rates, One-Euro, outlier gate, Chai)
* ``defaults``    — automatic default training against the synthetic performer
* ``puppet``      — tracker → filter → expression maps → renderer, frame by frame

The expression maps themselves live in ``morph.expression_map`` (the paper's) and ``morph.mappers``.
"""
