"""The campaign's Welch spectrum (campaign/stats.welch) against SciPy's, which it replaces."""
import numpy as np
import pytest
from scipy import signal

from jaxslosh.campaign.stats import frequencies, segment_length, welch


@pytest.mark.parametrize("n", [16, 17, 101, 1000, 6001])
def test_welch_is_scipys(n):
    """Even and odd records and segments, a mean to remove: SciPy's density to round-off, on the
    frequency grid the campaign file holds."""
    rng = np.random.default_rng(n)
    dt = 0.1
    y = np.sin(1.3 * dt * np.arange(n)) + rng.normal(size=n) + 0.3
    f, p = signal.welch(y, fs=1.0 / dt, nperseg=segment_length(n), detrend="constant")
    q = welch(y, dt, segment_length(n))
    assert q.shape == p.shape
    assert np.max(np.abs(q - p)) <= 1e-12 * np.max(p)
    assert np.allclose(2.0 * np.pi * f, frequencies(n, dt), rtol=1e-14, atol=0.0)
