"""Physical ranges of the strain-side effects' parameters, with their sources.

The effects of :mod:`.effects` declare them as :attr:`swgcal.terms.FitTerm.ranges`; a fit
outside its range is not accepted as the effect (acceptance rule 4 of
:mod:`swgcal.loop`): the term would be absorbing something else, and a run
where such a candidate still passes the evidence rule ends ``unexplained``. Each bound
is an upper bound of what the named mechanism can produce, from a data sheet, a
catalogue or a closed form; where a number is an assumption of this project, the text
says so.
"""

from __future__ import annotations

__all__ = ["OFFSET_RANGE_MVV", "DRIFT_RANGE_MVV_S", "GAIN_RANGE", "MISPLACEMENT_RANGE_DEG",
           "BRIDGE_K_RANGE", "LOWPASS_RANGE_HZ", "KE_RANGE_RAD"]

OFFSET_RANGE_MVV = 2.84
"""Largest |offset| [mV/V]: the input range of the bench preset's converter (TI
ADS131M04 at gain 128, 1.2 V reference, 3.3 V excitation, :mod:`swgsim.sensing.acquisition`);
a larger zero offset would clip the channel."""
DRIFT_RANGE_MVV_S = 1e-3
"""Largest |zero drift rate| [mV/V/s]: thermal output of self-temperature-compensated
gauges within ±1.8 µε/K (Kyowa SELCOM data; Vishay Micro-Measurements TN-504) times a
warm-up rate of 1 K/s (a flexspline heating by 60 K in a minute: an upper bound, not a
typical value), in a quarter bridge of gauge factor 2 (0.5e-3 mV/V per µε): 9e-4,
rounded up. Half and full bridges cancel most of it."""
GAIN_RANGE = 0.10
"""Largest |relative channel gain| [-]: gauge-factor tolerance ±1 % (foil-gauge data
sheets), amplifier gain error (a fraction of a per cent for the ADS131M04), lead-wire
desensitisation R_g / (R_g + R_lead) (1 Ω of lead on a 120 Ω gauge: 0.8 %) and the grid's
position on the flexspline's strain gradient (assumption: a few per cent); summed, with
a margin of about two."""
MISPLACEMENT_RANGE_DEG = 5.0
"""Largest |gauge misplacement| along θ [deg]: a hand-bonded gauge sits within about a
millimetre of its mark (assumption; ≈ 2° on the ~30 mm collar radius) and its grid
within ±2° of its intended orientation (Vishay Micro-Measurements TN-511; DTIC report
ADA801368 on rosette misalignment of ±2°); 5° leaves margin for a marking error."""
BRIDGE_K_RANGE = 2e-3
"""Largest |bridge nonlinearity k| [1/(mV/V)]: the exact quarter bridge,
s/(1 + 2e-3 s) in mV/V, independent of the gauge factor (Hoffmann 1989, ch. on the
Wheatstone bridge; :data:`swgsim.sensing.effects.QUARTER_BRIDGE_K`); half and full bridges
with opposite arm strains are more linear."""
LOWPASS_RANGE_HZ = (0.262 * 250.0, 0.262 * 64e3)
"""Range of the amplifier corner frequency [Hz]: the −3 dB corner 0.262 f_DATA of the
sinc3 filter of the bench preset's converter (TI ADS131M04 data sheet SBAS890, digital
filter) over its data rates 250 SPS to 64 kSPS. Another amplifier needs its own range."""
KE_RANGE_RAD = 2.9e-4
"""Largest extra kinematic-error amplitude [rad]: 1 arcmin, the positioning accuracy
(peak-to-peak over an output revolution) of Harmonic Drive CSF/CSG size 20 at ratios
≥ 50 (catalogue "CSF & CSG series", engineering data, positioning accuracy table:
2.9e-4 rad standard, 1.5e-4 rad special); a harmonic of amplitude A alone is 2A
peak-to-peak, so this allows twice the catalogue value (scatter, wear)."""
