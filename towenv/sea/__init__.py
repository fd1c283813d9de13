"""Sea states, wave spectra and random-phase time-series synthesis.

Conventions (``shared/reference/sea-and-vessel.md``): omega in rad/s, S(omega) in
m^2 s/rad, ``Hs = 4 sqrt(m0)``; wave headings are *propagation* directions
relative to the ship's forward axis (180 deg = head seas).

Typical use::

    from towenv.sea import SeaState, synthesize
    sea = SeaState.from_code(3, "coastal", heading_deg=180)
    rec = synthesize(sea, duration=1800.0, seed=env.np_random)
    grid = rec.precompute(dt=0.02, track=(x_ship, y_ship))   # or rec.elevation(t, x, y)
"""

from .spectra import (
    COASTAL_TP_COEFF,
    COASTAL_TP_COEFF_RANGE,
    G,
    LEE_OPEN_OCEAN,
    PM_ALPHA,
    PM_BETA,
    SPECTRUM_KINDS,
    SPREADING_KINDS,
    WMO_SEA_STATE,
    SeaState,
    bretschneider,
    bretschneider_coefficients,
    cos2s_halfplane_spreading,
    cos2s_spreading,
    dnv_gamma,
    dnv_tz_over_tp,
    fetch_limited_parameters,
    hm0_from_m0,
    integrate_moments,
    jonswap,
    jonswap_fetch_limited,
    jonswap_m0_ratio,
    jonswap_normalisation,
    peak_frequency,
    pierson_moskowitz,
    pierson_moskowitz_wind,
    pm_hs_from_wind,
    pm_tp_from_hs,
    pm_tp_from_wind,
    spectral_moments,
    spreading_function,
    t1_from_moments,
    tp_from_t1,
    tp_from_tz,
    tz_from_moments,
)
from .synthesis import (
    GriddedWave,
    WaveRecord,
    default_omega_range,
    integrate_track,
    synthesize,
    wavenumber,
)

__all__ = [
    "COASTAL_TP_COEFF",
    "COASTAL_TP_COEFF_RANGE",
    "G",
    "LEE_OPEN_OCEAN",
    "PM_ALPHA",
    "PM_BETA",
    "SPECTRUM_KINDS",
    "SPREADING_KINDS",
    "WMO_SEA_STATE",
    "SeaState",
    "bretschneider",
    "bretschneider_coefficients",
    "cos2s_halfplane_spreading",
    "cos2s_spreading",
    "dnv_gamma",
    "dnv_tz_over_tp",
    "fetch_limited_parameters",
    "hm0_from_m0",
    "integrate_moments",
    "jonswap",
    "jonswap_fetch_limited",
    "jonswap_m0_ratio",
    "jonswap_normalisation",
    "peak_frequency",
    "pierson_moskowitz",
    "pierson_moskowitz_wind",
    "pm_hs_from_wind",
    "pm_tp_from_hs",
    "pm_tp_from_wind",
    "spectral_moments",
    "spreading_function",
    "t1_from_moments",
    "tp_from_t1",
    "tp_from_tz",
    "tz_from_moments",
    "GriddedWave",
    "WaveRecord",
    "default_omega_range",
    "integrate_track",
    "synthesize",
    "wavenumber",
]
