"""The measurement chain: what happens between the flexspline's strain and the recorded
numbers.

- :mod:`~swgsim.sensing.effects` - measurement-chain effects on windows (gauge placement,
  bridge nonlinearity, gains, filters, delays, offsets, drift: ``sensor_effects``);
  :mod:`~swgsim.sensing.dsp` - their signal-processing primitives;
- :mod:`~swgsim.sensing.acquisition` - window starts and the bench amplifier (sinc3
  filter, noise, 24-bit converter);
- :mod:`~swgsim.sensing.angles` - input angle sensor and output encoder, ψ and the twist
  estimated from them;
- :mod:`~swgsim.sensing.disturbance` - the paper's eq. (10) offsets and sub-harmonics;
- :mod:`~swgsim.sensing.sensor_faults` - faults of a bridge (offset step, gain drift).
"""
