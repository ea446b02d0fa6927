"""The gear and its physics: what is simulated before any sensor reads it.

- :mod:`~swgsim.gear.dynamics` - the dynamic I/O model, paper eq. (1)-(6), steady windows;
  :mod:`~swgsim.gear.modes` - linearised at steady motion (torsional mode, RK4 step);
  :mod:`~swgsim.gear.profile` and :mod:`~swgsim.gear.profile_dynamics` - operating
  profiles (moves, holds, loads) and the model along them;
- :mod:`~swgsim.gear.flexspline` - the flexspline as a space truss (Sec. II-B);
  :mod:`~swgsim.gear.influence` - influence functionals of the gauges, Woodbury updates;
  :mod:`~swgsim.gear.sensors` - surface strain, gauge grids, bridges, layouts;
  :mod:`~swgsim.gear.chain` - the simulation chain dynamics -> truss -> gauges;
- :mod:`~swgsim.gear.faults` - the paper's five faults and wear as parameter transforms;
  :mod:`~swgsim.gear.friction` - joint friction beyond the paper law;
  :mod:`~swgsim.gear.terms` - model terms shared with the calibration loop.
"""
