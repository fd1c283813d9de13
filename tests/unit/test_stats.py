"""Tests of towenv.stats against closed forms (``sea-and-vessel.md`` section 6)
and thesis Table 6.1.  Monte-Carlo tolerances are ~4-5 standard errors."""

from __future__ import annotations

import csv
import math
import pathlib

import numpy as np
import pytest
from scipy import signal
from scipy.integrate import trapezoid

from towenv import stats

TWO_PI = 2 * math.pi


def _narrowband_gaussian(n, dt, w0, bw, m0, rng):
    """Gaussian process with a Gaussian-shaped narrow PSD (centre w0, std bw rad/s)
    by random complex Fourier coefficients (RAS); returns (x, omega, S)."""
    w = TWO_PI * np.fft.rfftfreq(n, dt)
    S = np.exp(-0.5 * ((w - w0) / bw) ** 2)
    S *= m0 / trapezoid(S, w)
    dw = w[1] - w[0]
    coef = 0.5 * np.sqrt(S * dw) * (rng.standard_normal(w.size) + 1j * rng.standard_normal(w.size))
    x = np.fft.irfft(coef * n, n)
    return x, w, S


# --------------------------------------------------------------------------
# closed forms
# --------------------------------------------------------------------------
def test_rayleigh_closed_forms_match_reference_table():
    # Reference (section 6): 2.002 (1/3), 2.545 (1/10), 3.336 (1/100), 3.97 (1/1000),
    # mean amplitude 1.253, level exceeded by 1/1000: 3.72 (all x sqrt(m0)).
    m0 = 2.5
    r = math.sqrt(m0)
    assert stats.rayleigh_mean_of_highest(1 / 3, m0) / r == pytest.approx(2.002, abs=0.0006)
    assert stats.rayleigh_mean_of_highest(1 / 10, m0) / r == pytest.approx(2.545, abs=0.0006)
    assert stats.rayleigh_mean_of_highest(1 / 100, m0) / r == pytest.approx(3.336, abs=0.0006)
    assert stats.rayleigh_mean_of_highest(1 / 1000, m0) / r == pytest.approx(3.97, abs=0.006)
    assert stats.rayleigh_mean_of_highest(1.0, m0) == pytest.approx(stats.rayleigh_mean_amplitude(m0))
    assert stats.rayleigh_mean_amplitude(m0) / r == pytest.approx(1.253, abs=0.0006)
    assert stats.rayleigh_exceedance_level(1 / 1000, m0) / r == pytest.approx(3.72, abs=0.006)
    d = stats.amplitude_statistics(m0)
    assert d["significant_amplitude"] == pytest.approx(2 * r)
    assert d["significant_height"] == pytest.approx(4 * r)
    assert d["rms"] == pytest.approx(r)
    assert d["mean_1_1000"] > d["level_1_1000"] > d["mean_1_100"] > d["mean_1_10"] > d["mean_1_3"]


def test_rms_and_significant_values_on_gaussian_data():
    rng = np.random.default_rng(0)
    sigma = 0.7
    x = 3.0 + sigma * rng.standard_normal(400_000)
    # std error of the sample std ~ sigma/sqrt(2N) = 0.11 %
    assert stats.rms(x, demean=True) == pytest.approx(sigma, rel=0.005)
    assert stats.rms(x) == pytest.approx(math.sqrt(9 + sigma**2), rel=0.005)
    assert stats.significant_amplitude(x) == pytest.approx(2 * sigma, rel=0.005)
    assert stats.significant_height(x) == pytest.approx(4 * sigma, rel=0.005)
    assert stats.significant_amplitude(m0=sigma**2) == pytest.approx(2 * sigma)
    t = np.linspace(0, 100, 100_001)
    assert stats.rms(2.0 * np.sin(TWO_PI * t)) == pytest.approx(2 / math.sqrt(2), rel=1e-4)
    with pytest.raises(ValueError, match="exactly one"):
        stats.significant_amplitude(x, m0=1.0)
    with pytest.raises(ValueError, match="m0 must be"):
        stats.significant_height(m0=-1.0)


def test_mean_of_highest_on_rayleigh_samples():
    rng = np.random.default_rng(1)
    m0 = 1.7
    a = rng.rayleigh(math.sqrt(m0), 400_000)
    for p in (1 / 3, 1 / 10, 1 / 100, 1 / 1000):
        # 1/1000 uses 400 samples: std error ~0.3/sqrt(400)/3.97 ~ 0.4 %
        assert stats.mean_of_highest(a, p) == pytest.approx(stats.rayleigh_mean_of_highest(p, m0), rel=0.02)
    with pytest.raises(ValueError, match="need at least 1000 values"):
        stats.mean_of_highest(a[:999], 1 / 1000)
    with pytest.raises(ValueError, match="fraction must be in"):
        stats.mean_of_highest(a, 0.0)


def test_most_probable_maximum_is_e_minus_1_quantile():
    # For N Rayleigh amplitudes, P(max <= sqrt(2 m0 ln N)) = (1 - 1/N)^N ~ e^-1.
    rng = np.random.default_rng(2)
    m0, N, trials = 0.9, 500, 4000
    mx = rng.rayleigh(math.sqrt(m0), (trials, N)).max(axis=1)
    mpm = stats.most_probable_maximum(m0, N)
    assert mpm == pytest.approx(math.sqrt(2 * m0 * math.log(N)))
    frac = np.mean(mx <= mpm)
    assert frac == pytest.approx((1 - 1 / N) ** N, abs=0.03)  # std error 0.0076
    # duration form: N = duration / Tz
    assert stats.most_probable_maximum(m0, duration=3 * 3600, tz=6.0) == pytest.approx(
        stats.most_probable_maximum(m0, 1800))
    with pytest.raises(ValueError):
        stats.most_probable_maximum(m0)
    assert stats.zero_crossing_period(1.0, 4 * math.pi**2 / 25) == pytest.approx(5.0)


def test_empirical_zero_crossing_statistics_on_narrowband_record():
    rng = np.random.default_rng(3)
    dt, n, m0 = 0.25, 1 << 20, 0.3  # ~73 h, ~41 000 waves
    x, w, S = _narrowband_gaussian(n, dt, 1.0, 0.04, m0, rng)
    zc = stats.zero_crossing_analysis(x, dt)
    m2 = trapezoid(w**2 * S, w)
    tz = TWO_PI * math.sqrt(m0 / m2)
    assert zc.tz == pytest.approx(tz, rel=0.01)
    assert zc.n_waves == pytest.approx(n * dt / tz, rel=0.02)
    d = stats.empirical_amplitude_statistics(x, dt)
    # sample variance of a narrow-band record: std error ~ sqrt(2*22 s/T) = 1.3 %
    # (22 s = int rho^2 d tau for bw = 0.04 rad/s), so 2 sqrt(m0) to within 3 %
    assert d["significant_amplitude"] == pytest.approx(2 * math.sqrt(m0), rel=0.03)
    # shape check against the record's own variance: narrow band (bandwidth
    # 4 % of w0), so crests are Rayleigh to within ~1-2 %
    r = math.sqrt(np.var(x))
    assert d["significant_amplitude"] == pytest.approx(2 * r, rel=1e-12)
    assert d["mean_1_3"] == pytest.approx(2.002 * r, rel=0.03)
    assert d["mean_1_10"] == pytest.approx(2.545 * r, rel=0.03)
    assert d["mean_1_1000"] == pytest.approx(3.97 * r, rel=0.05)
    h = stats.empirical_amplitude_statistics(x, dt, amplitude="half_height")
    assert h["mean_1_3"] == pytest.approx(2.002 * r, rel=0.03)
    # too short a record for 1/1000: NaN rather than a misleading number
    assert math.isnan(stats.empirical_amplitude_statistics(x[:4000], dt)["mean_1_1000"])


def test_zero_crossing_on_sine():
    dt = 0.01
    t = np.arange(0, 100, dt)
    zc = stats.zero_crossing_analysis(1.5 * np.sin(TWO_PI * t / 4.0 + 0.3) + 2.0, dt)
    assert zc.n_waves == 24
    np.testing.assert_allclose(zc.periods, 4.0, atol=1e-3)
    np.testing.assert_allclose(zc.crests, 1.5, atol=1e-3)
    np.testing.assert_allclose(zc.heights, 3.0, atol=2e-3)


# --------------------------------------------------------------------------
# PSD and transfer functions
# --------------------------------------------------------------------------
def test_welch_psd_units():
    rng = np.random.default_rng(4)
    dt, sigma = 0.1, 0.5
    x = sigma * rng.standard_normal(200_000)
    w, S = stats.welch_psd(x, dt, nperseg=1024)
    # white noise: one-sided S(omega) = sigma^2 dt / pi, integrates to the variance
    band = (w > 0.05 * w[-1]) & (w < 0.95 * w[-1])
    assert np.mean(S[band]) == pytest.approx(sigma**2 * dt / math.pi, rel=0.01)
    assert stats.psd_moments(w, S, (0,))[0] == pytest.approx(np.var(x), rel=0.01)
    assert w[-1] == pytest.approx(math.pi / dt)
    # sine of amplitude A: m0 = A^2/2, peak at its angular frequency
    t = np.arange(0, 2000, dt)
    w, S = stats.welch_psd(2.0 * np.cos(1.3 * t), dt, nperseg=4096)
    assert stats.hm0_from_psd(w, S) == pytest.approx(4 * math.sqrt(2.0), rel=0.01)
    assert w[np.argmax(S)] == pytest.approx(1.3, abs=w[1] - w[0])


def test_rao_estimator_recovers_linear_filter():
    rng = np.random.default_rng(5)
    dt = 0.1
    fs = 1 / dt
    x = rng.standard_normal(2**17)
    b, a = signal.butter(2, 0.8, fs=fs)  # 0.8 Hz 2nd-order low-pass
    y = signal.lfilter(b, a, x)
    est = stats.estimate_rao(x, y, dt, nperseg=1024)
    f = est.omega / TWO_PI
    _, Htrue = signal.freqz(b, a, worN=f, fs=fs)
    good = est.reliable(0.99) & (f > 0) & (f < 2.0)
    assert good.sum() > 150  # 0-1.5 Hz: the pass band and well into the roll-off
    np.testing.assert_allclose(est.gain[good], np.abs(Htrue[good]), rtol=0.02)
    np.testing.assert_allclose(np.degrees(np.angle(est.rao[good] / Htrue[good])), 0.0, atol=2.0)

    # gain 2 and a 5-sample delay: H = 2 exp(-i omega tau); with output noise
    # H1 stays unbiased and the coherence flags the noise
    lag = 5
    y2 = 2.0 * np.concatenate((np.zeros(lag), x[:-lag])) + 1.0 * rng.standard_normal(x.size)
    est = stats.estimate_rao(x, y2, dt, nperseg=1024)
    band = (est.omega > 0.2) & (est.omega < 25)
    np.testing.assert_allclose(est.gain[band], 2.0, rtol=0.1)
    expected_phase = np.angle(np.exp(-1j * est.omega[band] * lag * dt))
    np.testing.assert_allclose(np.angle(est.rao[band] * np.exp(-1j * expected_phase)), 0.0, atol=0.1)
    # coherence = 4/(4 + 1) = 0.8 for unit-variance output noise
    assert np.median(est.coherence[band]) == pytest.approx(0.8, abs=0.03)


# --------------------------------------------------------------------------
# rate limits
# --------------------------------------------------------------------------
def test_rate_limits_match_table_6_1():
    assert stats.RATE_LIMITS == {
        "surge": (1.0, "m/s"), "sway": (1.0, "m/s"), "heave": (1.0, "m/s"),
        "roll": (6.28, "deg/s"), "pitch": (6.28, "deg/s"), "yaw": (1.05, "deg/s"),
    }
    path = pathlib.Path("/work/shared/reference/data/table_6_1_rate_limits.csv")
    if not path.exists():
        pytest.skip("shared reference data not available")
    with path.open() as fh:
        for row in csv.DictReader(fh):
            limit, unit = stats.RATE_LIMITS[row["motion"]]
            assert limit == float(row["rate_limit"]) and unit == row["unit"]


def test_rate_limit_check():
    t = np.linspace(0, 10, 1001)
    rep = stats.rate_limit_check({
        "heave": 1.2 * np.sin(t),               # peaks 1.2 m/s > 1 m/s
        "surge": 0.5,                           # scalar, fine
        "pitch": np.radians(5.0) * np.cos(t),   # 5 deg/s in rad/s: fine
        "Yaw": np.radians(1.2) * np.ones(5),    # 1.2 deg/s > 1.05; case-insensitive
    })
    assert rep["heave"].exceeded and rep["heave"].max_abs == pytest.approx(1.2, rel=1e-3)
    # fraction of time |1.2 sin t| > 1 over [0, 10]
    assert rep["heave"].fraction_over == pytest.approx(np.mean(np.abs(1.2 * np.sin(t)) > 1.0))
    assert rep["surge"].ok and rep["surge"].fraction_over == 0.0
    assert rep["pitch"].ok and rep["pitch"].max_abs == pytest.approx(5.0) and rep["pitch"].unit == "deg/s"
    assert rep["yaw"].exceeded and rep["yaw"].fraction_over == 1.0
    deg = stats.rate_limit_check({"roll": [6.0, -6.5]}, angular_unit="deg/s")
    assert deg["roll"].exceeded and deg["roll"].fraction_over == 0.5
    with pytest.raises(ValueError, match="is not one of"):
        stats.rate_limit_check({"bob": 1.0})
    with pytest.raises(ValueError, match="angular_unit"):
        stats.rate_limit_check({"roll": 1.0}, angular_unit="rpm")
    with pytest.raises(ValueError, match="finite"):
        stats.rate_limit_check({"roll": [np.nan]})
