# A clamped Al plate (0.2 x 0.05 m, 20x5 quads, t = 1 mm, two circular holes) under a 10 N tip
# load: at h = 5e-4 the first step jumps to a state with 1.5 kJ strain energy and the tip 35 mm
# shorter, and the run is reported 'complete'. h = 1e-3 and h = 2.5e-4 stay near 2e-4 J.
import lsmbs, numpy as np
import pathlib
c = lsmbs.load_case(pathlib.Path(__file__).with_name("case.json"))  # saved by lsmbs.ModelBuilder
c.simulation.t_end = 0.01
for h in (1e-3, 5e-4, 2.5e-4):
    c.simulation.h = h
    s = lsmbs.simulate(c, design=[0.002, 0.0153294])   # a design MMA visited (inside the bounds)
    i = int(round(1e-3 / h))
    print(f"h={h:g}: status={s.status}  strain energy at t=1 ms: {s.column('se')[i]:.3g} J  "
          f"max over run: {s.column('se').max():.3g} J  tip.x at 1 ms: {s.column('tip.x')[i]:.4f} (0.2000 at t=0)")
