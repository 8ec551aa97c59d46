"""Independent check of the C++ TDORC against a direct numpy/scipy
implementation of paper 000 eq. 4-11, sample by sample, for all three modes.

The reference is written from the equations, not from the C++ code:
  - drift line a*t + b by np.polyfit(t, S_r, 1) over the window, t counted
    from the window's first sample (eq. 4, 6, 7);
  - S_c = S_r - (a*t + b) with t of the current sample (eq. 5);
  - re-fit only while the whisker was not in contact at the previous sample
    (TDORC, eq. 8); TDOC fits once on the first n samples; band-pass mode
    uses S_c = S_r;
  - S_p by scipy.signal.lfilter (transposed direct form II, eq. 9-11), started
    at lfilter_zi * first input (steady state), one sample at a time.
The C++ side runs through the tdorc_csv test helper (path in $TDORC_CSV).
"""
import os
import subprocess

import numpy as np
import pytest
from scipy.signal import lfilter, lfilter_zi

B = np.array([0.0564, 0.0, -0.0564])
A = np.array([1.0, -1.8865, 0.8872])


def synthetic_trace(seed=1, n=3000, rate=50.0, contact_amp=600.0, contact_end=1650):
    """Three barometer channels: offsets, thermal drift whose slope changes,
    noise, propeller ringing and one contact episode (samples 1400-contact_end)."""
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    t = k / rate
    offsets = np.array([100000.0, 99520.0, 100810.0])
    drift = np.stack([
        8.0 * t - 0.05 * t ** 2,
        -5.0 * t + 30.0 * np.sin(t / 9.0),
        3.0 * t + 0.02 * t ** 2,
    ], axis=1)
    ringing = 2.0 * np.sin(2 * np.pi * 7.0 * t)[:, None]
    noise = rng.normal(0.0, 1.0, size=(n, 3))
    # contact: 0.1 s raised-cosine rise, 4.8 s hold, 0.1 s fall
    rise = np.clip((k - 1400) / 5.0, 0.0, 1.0) * np.clip((contact_end - k) / 5.0, 0.0, 1.0)
    contact = contact_amp * np.sin(0.5 * np.pi * rise) ** 2
    gains = np.array([1.0, 0.6, 0.2])
    return offsets + drift + ringing + noise + contact[:, None] * gains


def reference(S, mode, n=100, threshold=20.0, absolute=False, delay=0, hold=False, max_hold=1000, release=0.0,
              release_samples=1, drop=0.0, level_samples=25, max_slope=0.0, quiet_rms=0.0, quiet_samples=25):
    """delay, hold, max_hold, release, release_samples, drop, level_samples, max_slope,
    quiet_rms, quiet_samples: the README's sustained-contact extension (learn_delay,
    contact_hold, max_contact_hold, hold_release_fraction, hold_release_samples,
    hold_release_drop, hold_level_samples, max_drift_slope, hold_quiet_rms,
    hold_quiet_samples); defaults = eq. 8 as written."""
    N = S.shape[0]
    rows = np.zeros((N, 12))
    window = []          # sample indices in the least-squares window
    pending = []         # free samples waiting `delay` samples before entering the window
    fit = None           # (slope[3], intercept[3], first index[3])
    zi = None
    prev_contact, run = False, 0   # contact at the previous sample, samples since its onset
    peak = np.zeros(3)             # largest S_c per channel during the current contact
    below = 0                      # consecutive held samples with no channel over the hold condition
    level = 0.0                    # recent level of sum(S_c) during the current contact
    sums = []                      # sum(S_c) of the ready samples (hold_quiet_rms)
    for k in range(N):
        # 1. compensate with the fit of the previous samples
        if mode == "bandpass":
            sc = S[k].copy()
        elif fit is not None:
            slope, intercept, first = fit
            sc = S[k] - (slope * (k - first) + intercept)  # eq. 4, 5
        else:
            sc = None  # first window filling: not ready, zeros
        contact = any_sp = False
        if sc is not None:
            if zi is None:
                zi = [lfilter_zi(B, A) * sc[ch] for ch in range(3)]
            sp = np.zeros(3)
            for ch in range(3):
                y, zi[ch] = lfilter(B, A, [sc[ch]], zi=zi[ch])  # eq. 9-11
                sp[ch] = y[0]
            ch_contact = np.abs(sp) > threshold if absolute else sp > threshold
            contact = bool(ch_contact.any())
            any_sp = contact
            sums.append(sc.sum())
            changes = np.diff(sums[-(quiet_samples + 1):])
            quiet = quiet_rms > 0.0 and len(changes) == quiet_samples and \
                float(np.sum(changes ** 2)) < quiet_samples * quiet_rms ** 2  # RMS of the changes < quiet_rms
            if hold and mode != "bandpass" and not contact and prev_contact and run < max_hold:
                over = bool(((sc > threshold) & (sc > release * peak)).any())  # held while S_c is over T_c
                if drop > 0.0:
                    over = over and sc.sum() > drop * level  # ... and the whisker's S_c has not fallen
                if quiet:
                    over = False  # ... and has not gone quiet
                below = 0 if over else below + 1
                contact = below < release_samples  # ... and until release_samples samples were not
            frozen = mode == "tdorc" and contact
            rows[k] = [1, contact, frozen, *sc, *sp, *ch_contact]
        if not contact or any_sp:
            below = 0
        run = run + 1 if contact else 0
        peak = np.maximum(peak, sc) if (contact and sc is not None) else np.zeros(3)
        if contact and sc is not None:
            level = sc.sum() if run == 1 else level + (sc.sum() - level) / level_samples
        else:
            level = 0.0
        prev_contact = contact
        # 2. learn: first window, then (TDORC) re-fit while not in contact (eq. 8),
        #    with the sample of `delay` samples ago; a contact drops the waiting ones
        refit = False
        if mode != "bandpass":
            if fit is None:
                window.append(k)
                refit = len(window) == n
            elif mode == "tdorc" and contact:
                pending = []
            elif mode == "tdorc":
                pending.append(k)
                if len(pending) > delay:
                    window.append(pending.pop(0))
                    window = window[-n:]
                    refit = True
        if refit:
            t = np.array(window) - window[0]
            coef = [np.polyfit(t, S[window, ch], 1) for ch in range(3)]  # eq. 6, 7
            new = (np.array([c[0] for c in coef]), np.array([c[1] for c in coef]), np.full(3, window[0]))
            if fit is None or max_slope <= 0.0:
                fit = new
            else:  # a channel's fit steeper than max_slope is not used: that channel keeps its line
                use = np.abs(new[0]) <= max_slope
                fit = tuple(np.where(use, n_, o_) for n_, o_ in zip(new, fit))
    return rows


def run_cpp(S, mode, n=100, threshold=20.0, absolute=False, delay=0, hold=False, max_hold=1000, release=0.0,
            release_samples=1, drop=0.0, level_samples=25, max_slope=0.0, quiet_rms=0.0, quiet_samples=25):
    exe = os.environ.get("TDORC_CSV")
    if not exe:
        pytest.skip("TDORC_CSV not set (run through ctest)")
    text = "\n".join(",".join(repr(float(v)) for v in row) for row in S) + "\n"
    res = subprocess.run([exe, mode, str(n), repr(threshold), "1" if absolute else "0",
                          str(delay), "1" if hold else "0", str(max_hold), repr(float(release)), str(release_samples),
                          repr(float(drop)), str(level_samples), repr(float(max_slope)),
                          repr(float(quiet_rms)), str(quiet_samples)],
                         input=text, capture_output=True, text=True, check=True)
    return np.array([[float(v) for v in line.split(",")] for line in res.stdout.strip().splitlines()])


def assert_cpp_matches_reference(cpp, ref, S):
    """The C++ run equals the reference: ready, contact, frozen and per-channel contact flags
    identical; S_c and S_p to 1e-9 relative to the magnitude the arithmetic runs on (the raw
    pressure for S_c = S_r - N_td, the value itself otherwise), as test_matches_reference."""
    np.testing.assert_array_equal(cpp[:, [0, 1, 2, 9, 10, 11]], ref[:, [0, 1, 2, 9, 10, 11]])
    scale = np.abs(S).max()
    for col in range(3, 9):
        np.testing.assert_allclose(cpp[:, col], ref[:, col], rtol=1e-9, atol=1e-9 * scale if col < 6 else 1e-9 * 100)


@pytest.mark.parametrize("mode", ["tdorc", "tdoc", "bandpass"])
@pytest.mark.parametrize("window,absolute", [(100, False), (37, True)])
def test_matches_reference(mode, window, absolute):
    S = synthetic_trace()
    ref = reference(S, mode, n=window, absolute=absolute)
    cpp = run_cpp(S, mode, n=window, absolute=absolute)
    assert cpp.shape == ref.shape
    # ready, contact, frozen and per-channel contact flags: identical.
    flags = [0, 1, 2, 9, 10, 11]
    np.testing.assert_array_equal(cpp[:, flags], ref[:, flags])
    # S_c and S_p: 1e-9 relative to the magnitude the arithmetic runs on
    # (the raw pressure for S_c = S_r - N_td, the value itself otherwise).
    scale = np.abs(S).max()
    for col in range(3, 9):
        np.testing.assert_allclose(cpp[:, col], ref[:, col], rtol=1e-9, atol=1e-9 * scale if col < 6 else 1e-9 * 100)
    # The trace really exercises the modes.
    assert ref[:, 1].any(), "the contact episode must be detected"
    if mode == "tdorc":
        assert ref[:, 2].any(), "the drift must be frozen during contact"
        assert not ref[:1400, 1].any(), "TDORC: no false positive before the contact"
        if not absolute:
            # (With |S_p| > T the release undershoot keeps the fit frozen
            # while the extrapolated drift line diverges: see README.)
            assert not ref[2000:, 1].any(), "TDORC: contact ends after the release"


@pytest.mark.parametrize("mode", ["tdorc", "tdoc", "bandpass"])
@pytest.mark.parametrize("delay,hold,max_hold,release",
                         [(10, True, 1000, 0.0), (3, True, 40, 0.0), (0, True, 1000, 0.0), (10, False, 1000, 0.0),
                          (10, True, 1000, 0.25), (10, True, 1000, 0.9)])
def test_sustained_contact_extension_matches_reference(mode, delay, hold, max_hold, release):
    # A 20 s push (samples 1400-2400): S_p alone decays below T_c long before it ends.
    S = synthetic_trace(contact_amp=200.0, contact_end=2400)
    ref = reference(S, mode, delay=delay, hold=hold, max_hold=max_hold, release=release)
    cpp = run_cpp(S, mode, delay=delay, hold=hold, max_hold=max_hold, release=release)
    assert_cpp_matches_reference(cpp, ref, S)
    if mode == "tdorc" and hold:
        # The hold changes the result on this trace (the comparison is not vacuous).
        assert (ref[:, 1] != reference(S, mode)[:, 1]).any()


def slipping_trace(period=53):
    """The 20 s push of the sustained-contact test with stick-slip: every
    `period`-th pressed sample is a slip sample whose load drops to zero."""
    pressed = synthetic_trace(contact_amp=200.0, contact_end=2400)
    free = synthetic_trace(contact_amp=0.0)
    S = pressed.copy()
    slips = np.arange(1410, 2390, period)
    S[slips] = free[slips]
    return S, slips


@pytest.mark.parametrize("release_samples", [1, 3, 10])
def test_hold_release_samples_matches_reference(release_samples):
    S, _ = slipping_trace()
    ref = reference(S, "tdorc", delay=10, hold=True, release_samples=release_samples)
    cpp = run_cpp(S, "tdorc", delay=10, hold=True, release_samples=release_samples)
    assert_cpp_matches_reference(cpp, ref, S)


def test_hold_release_samples_bridges_slip_samples():
    """One slip sample releases a held contact with release_samples = 1, and the
    pressed samples that follow are learned as drift; with 3 the contact lasts
    through every slip to the end of the push, and still ends after it."""
    S, slips = slipping_trace()
    one = reference(S, "tdorc", delay=10, hold=True, release_samples=1)
    three = reference(S, "tdorc", delay=10, hold=True, release_samples=3)
    pushed = slice(1404, 2395)  # onset at 1404 (S_p > T_c), last pressed sample 2399
    assert not one[pushed, 1].all(), "a slip sample must release the paper-length hold"
    assert three[pushed, 1].all(), "release_samples = 3 keeps the contact through the slips"
    assert not three[2420:, 1].any(), "and releases it after the push"
    # The bridged run never learns a pressed sample: S_c after the push is the drift error only.
    assert np.abs(three[2500:, 3:6]).max() < 10.0
    assert np.abs(one[2500:, 3:6]).max() > np.abs(three[2500:, 3:6]).max()


def hysteresis_trace(offset=40.0, tau=750.0, end=2000):
    """A 12 s push (samples 1400-2000), then the gel's partial recovery (000
    eq. 1, N_h): an offset of `offset` Pa on channel 0 (scaled by the channel
    gains) decaying with `tau` samples after the release."""
    S = synthetic_trace(contact_amp=200.0, contact_end=end)
    k = np.arange(S.shape[0])
    after = np.where(k >= end, offset * np.exp(-(k - end) / tau), 0.0)
    return S + after[:, None] * np.array([1.0, 0.6, 0.2])


@pytest.mark.parametrize("drop,level_samples", [(0.0, 25), (0.25, 50), (0.25, 1), (0.6, 25)])
def test_hold_release_drop_matches_reference(drop, level_samples):
    S = hysteresis_trace()
    kw = dict(delay=10, hold=True, max_hold=2000, release=0.1, release_samples=3, drop=drop, level_samples=level_samples)
    ref = reference(S, "tdorc", **kw)
    cpp = run_cpp(S, "tdorc", **kw)
    assert_cpp_matches_reference(cpp, ref, S)


def test_hold_release_drop_ends_a_hold_over_hysteresis():
    """The hysteresis offset (40 Pa, over T_c and 0.1 of the peak; with the
    drift-line error S_c is 27 / 33 / 13 Pa on the three channels after the
    release) holds a released whisker to the end of the trace with the
    fraction rule alone; the drop rule (sum of S_c below 0.25 of its 1 s
    level) releases it right after the push."""
    S = hysteresis_trace()
    kw = dict(delay=10, hold=True, max_hold=2000, release=0.1, release_samples=3)
    without = reference(S, "tdorc", **kw)
    with_drop = reference(S, "tdorc", drop=0.25, level_samples=50, **kw)
    assert without[1404:, 1].all(), "the offset holds the contact with the fraction rule alone"
    assert with_drop[1404:2000, 1].all(), "the drop rule keeps the 12 s push in contact"
    assert not with_drop[2010:, 1].any(), "and releases it within a few samples of the push's end"


@pytest.mark.parametrize("quiet_rms,quiet_samples", [(0.0, 25), (8.0, 25), (3.0, 25), (8.0, 50)])
def test_hold_quiet_rms_matches_reference(quiet_rms, quiet_samples):
    """hold_quiet_rms (issue 17) on the hysteresis trace, C++ against the
    reference sample by sample. The trace's push is a constant +200 Pa (no
    motion): its S_c changes by the noise and the 7 Hz ringing only (RMS of
    the sum's changes ~4-5 Pa), so with 8 Pa it is released as soon as the
    band-pass lets the hold decide, as is the hysteresis offset after it: the
    rule relies on a pressed whisker moving with the drone."""
    S = hysteresis_trace()
    kw = dict(delay=10, hold=True, max_hold=2000, release=0.1, release_samples=3, drop=0.25, level_samples=50,
              quiet_rms=quiet_rms, quiet_samples=quiet_samples)
    ref = reference(S, "tdorc", **kw)
    cpp = run_cpp(S, "tdorc", **kw)
    assert_cpp_matches_reference(cpp, ref, S)
    held = ref[1404:2000, 1]
    if quiet_rms == 8.0:
        assert not held.all(), "a motionless push is quiet: released before its end"
    if quiet_rms == 0.0:
        assert held.all(), "without the rule the 12 s push stays in contact"


@pytest.mark.parametrize("hold", [False, True])
def test_max_drift_slope_matches_reference(hold):
    """A 10 s push under eq. 8 as written (hold False) locks the whisker after the
    release: the window learned pressed samples, the line through the step is
    steep and its frozen ramp holds S_p over T_c. The slope bound prevents it;
    C++ and the reference agree sample by sample either way."""
    S = synthetic_trace(contact_amp=200.0, contact_end=1900)
    kw = dict(delay=10 if hold else 0, hold=hold, release=0.1 if hold else 0.0, release_samples=3 if hold else 1)
    ref = reference(S, "tdorc", max_slope=0.5, **kw)
    cpp = run_cpp(S, "tdorc", max_slope=0.5, **kw)
    assert_cpp_matches_reference(cpp, ref, S)
    if not hold:
        assert reference(S, "tdorc", **kw)[2900:, 1].all(), "eq. 8 as written locks on this push"
        assert not ref[2200:, 1].any(), "the bound keeps the steep line out"


def test_tdorc_has_no_false_positives_in_free_flight():
    """Extended Data Fig. 2c in miniature: free flight only, FPR of TDORC is 0
    and not above TDOC's or band-pass's (paper: 0 %, 12.23 %, 38.24 %)."""
    S = synthetic_trace(seed=3, contact_amp=0.0)
    fpr = {m: reference(S, m)[100:, 1].mean() for m in ["tdorc", "tdoc", "bandpass"]}
    assert fpr["tdorc"] == 0.0
    assert fpr["tdoc"] >= fpr["tdorc"]
    assert fpr["bandpass"] >= fpr["tdorc"]


def test_reference_catches_wrong_coefficient():
    """The comparison can fail: a different a1 gives a visible mismatch."""
    S = synthetic_trace()
    ref = reference(S, "tdorc")
    global A
    saved = A.copy()
    try:
        A = np.array([1.0, -1.8860, 0.8872])
        other = reference(S, "tdorc")
    finally:
        A = saved
    assert np.abs(other[:, 6:9] - ref[:, 6:9]).max() > 1e-3
