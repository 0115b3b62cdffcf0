"""Stepped-sine analysis: the response at each step's frequency, in steady state.

A stepped-sine test holds one frequency at a time. After each change of frequency the
response carries a transient (the structure's free decay at its own frequencies, decaying
with the time constant ``1 / (zeta omega)`` of the modes nearby) on top of the steady state
at the drive frequency. Per step, :func:`step_amplitudes` therefore

1. discards the first half of the dwell (the settling; :data:`FIT_FRACTION`);
2. fits a constant and a cosine and a sine at the drive frequency and its harmonics by least
   squares over the largest whole number of periods that ends with the step: with whole
   periods this is the DFT at the drive frequency, into which harmonic distortion does not
   leak, and the harmonics' own amplitudes come with it;
3. repeats the fit on the first and the last half of those periods: a transient that is
   still decaying shows as a difference between the two (``settled_db``).

An FRF line is the ratio of the response's and the excitation's complex amplitudes at the
drive frequency, both from the same window, so the phase reference cancels
(:func:`stepped_frf`). This is the steady-state (first-harmonic) FRF of stepped-sine testing
(Ewins 2000, *Modal Testing*, stepped-sine excitation; for a nonlinear structure the
describing-function FRF at the drive amplitude, Worden & Tomlinson 2001, Ch. 2).

Steps come from a simulated excitation's instantaneous frequency (:func:`steps_of`,
piecewise constant) or, in a rig's record, from the phase of the excitation itself
(:func:`detect_steps`).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.signal import butter, hilbert, sosfiltfilt

from ..errors import SignalError
from ._checks import as_signal, same_length

#: the part of each step that is fitted (its end); the rest lets the transient decay
FIT_FRACTION = 0.5
#: harmonics fitted with the fundamental (below 0.45 fs)
ORDERS = (1, 2, 3)
#: a detected step shorter than this fraction of a neighbour is no step of its own
SHORTEST = 0.5
#: neighbouring steps closer than this (relative) are one: the analytic signal's phase
#: bends within a step where the steps are finer than its leakage (1 / step, e.g. 4 s for
#: 0.25 Hz steps) and may split one step into two of nearly the same frequency
RESOLUTION = 1e-3


@dataclass(frozen=True)
class Step:
    """One step of a stepped sine: from ``start`` to ``end`` (s) at ``frequency`` (Hz)."""

    start: float
    end: float
    frequency: float


@dataclass
class SteppedFRF:
    """The steady-state response of a stepped-sine record, one entry per step in the order
    driven.

    ``frf[ch]``: complex ratio response / excitation at the step frequency; ``amplitudes[ch]``:
    complex amplitudes of the response at orders :data:`ORDERS` (``(n, len(ORDERS))``, NaN
    above 0.45 fs), ``x(t) = Re(X e^{i 2 pi k f t})``; ``settled_db[ch]``: the difference of
    the line between the first and the last half of the fitted periods (dB; NaN where the
    step holds a single period).
    """

    f: np.ndarray
    force: np.ndarray
    frf: dict[str, np.ndarray]
    amplitudes: dict[str, np.ndarray] = field(default_factory=dict)
    settled_db: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def direction(self) -> str | None:
        """``"up"``/``"down"`` where the steps rise/fall throughout, else None."""
        return direction_of(self.f)


def direction_of(f: Sequence[float]) -> str | None:
    d = np.diff(np.asarray(f, float))
    if len(d) and np.all(d > 0):
        return "up"
    if len(d) and np.all(d < 0):
        return "down"
    return None


def steps_of(f_inst: np.ndarray | None, fs: float, max_changes: float = 0.01
             ) -> list[Step] | None:
    """The steps of a piecewise-constant instantaneous frequency (a simulated stepped sine,
    or a record whose steps :func:`detect_steps` found), or None when it is not one (a sweep
    changes at every sample: more than ``max_changes`` of them)."""
    if f_inst is None or len(f_inst) < 4:
        return None
    f = np.asarray(f_inst, float)
    change = np.flatnonzero(f[1:] != f[:-1]) + 1
    if len(change) > max_changes * len(f) or not np.all(np.isfinite(f)):
        return None
    edges = np.concatenate([[0], change, [len(f)]])
    return [Step(a / fs, b / fs, float(f[a])) for a, b in itertools.pairwise(edges)]


def _fit(x: np.ndarray, t: np.ndarray, f: float, orders: Sequence[int]) -> np.ndarray:
    """Complex amplitudes ``a_k - i b_k`` of ``c + sum a_k cos(2 pi k f t) + b_k sin(...)``
    (``x`` one record, or several as columns: then one row per order)."""
    w = 2 * np.pi * f * t
    cols = [np.ones_like(t)]
    for k in orders:
        cols += [np.cos(k * w), np.sin(k * w)]
    coef, *_ = np.linalg.lstsq(np.column_stack(cols), x, rcond=None)
    return coef[1::2] - 1j * coef[2::2]


def _window(step: Step, fs: float, n_max: int, fraction: float) -> tuple[int, int, int]:
    """(first sample, end sample, whole periods) of the fitted end of ``step``."""
    periods = int(np.floor(fraction * (step.end - step.start) * step.frequency + 1e-9))
    if step.end * fs > n_max + 0.5:  # clamping it would fit the samples before the step
        raise SignalError(f"the step at {step.frequency:.6g} Hz ends at {step.end:.6g} s, "
                          f"after the record's end ({n_max / fs:.6g} s)")
    end = int(np.floor(step.end * fs + 1e-9))
    if periods < 1:
        raise SignalError(f"the step at {step.frequency:.6g} Hz dwells "
                          f"{step.end - step.start:.4g} s: less than one period in its "
                          f"fitted {fraction:.0%}")
    return end - round(periods * fs / step.frequency), end, periods


def step_amplitudes(x: np.ndarray, fs: float, step: Step, orders: Sequence[int] = ORDERS,
                    fraction: float = FIT_FRACTION) -> tuple[np.ndarray, np.ndarray]:
    """(complex amplitudes at ``orders``, the same on the first and on the last half of the
    fitted periods: shape ``(2, len(orders))``) of ``x`` in ``step`` (module docstring);
    NaN for orders at or above 0.45 fs. ``x`` may hold several records as columns
    (``(n, m)``): the results then have a last axis of ``m``."""
    x = np.asarray(x, float)
    i0, i1, periods = _window(step, fs, len(x), fraction)
    ok = [k for k in orders if k * step.frequency < 0.45 * fs]
    rows = [list(orders).index(k) for k in ok]

    def amps(a, b):
        out = np.full((len(orders), *x.shape[1:]), np.nan + 0j)
        out[rows] = _fit(x[a:b], np.arange(a, b) / fs, step.frequency, ok)
        return out

    whole = amps(i0, i1)
    halves = np.full((2, *whole.shape), np.nan + 0j)
    if periods >= 2:
        m = round((periods // 2) * fs / step.frequency)
        halves = np.array([amps(i1 - 2 * m, i1 - m), amps(i1 - m, i1)])
    return whole, halves


def stepped_frf(force: np.ndarray, responses: dict[str, np.ndarray], fs: float,
                steps: Sequence[Step], orders: Sequence[int] = ORDERS,
                fraction: float = FIT_FRACTION) -> SteppedFRF:
    """The steady-state FRF of every response channel on ``steps`` (module docstring)."""
    if not steps:
        raise SignalError("a stepped-sine record needs at least one step")
    if 1 not in orders:
        raise SignalError(f"orders {tuple(orders)} must hold 1 (the FRF's line)")
    names = list(responses)
    force = as_signal(force, "force")
    for n in names:
        same_length(force, as_signal(responses[n], f"response {n!r}"), "force",
                    f"response {n!r}")
    k1 = list(orders).index(1)
    x = np.column_stack([force, *(responses[n] for n in names)])
    fits = [step_amplitudes(x, fs, s, orders, fraction) for s in steps]
    whole = np.array([w for w, _ in fits])  # (steps, orders, 1 + channels)
    halves = np.array([h[:, k1] for _, h in fits])  # (steps, 2, 1 + channels)
    fp = whole[:, k1, 0]
    if np.any(np.abs(fp) == 0):
        i = int(np.argmax(np.abs(fp) == 0))
        raise SignalError(f"the excitation is silent in the step at {steps[i].frequency:.6g} "
                          f"Hz")
    out = SteppedFRF(f=np.array([s.frequency for s in steps]), force=fp, frf={})
    with np.errstate(invalid="ignore", divide="ignore"):  # NaN: one period or less
        line = halves[:, :, 1:] / halves[:, :, :1]
        settled = 20 * np.log10(np.abs(line[:, 1]) / np.abs(line[:, 0]))
    for j, name in enumerate(names):
        out.amplitudes[name] = whole[:, :, j + 1]
        out.frf[name] = whole[:, k1, j + 1] / fp
        out.settled_db[name] = settled[:, j]
    return out


def _segments(x: np.ndarray, w: np.ndarray, penalty: float, min_size: int = 2
              ) -> list[tuple[int, int]]:
    """Optimal partition of ``x`` (weights ``w``: inverse variances) into pieces of
    constant mean: weighted least squares plus ``penalty`` per piece, pieces of
    ``min_size`` or more (optimal partitioning, Jackson et al. 2005, with the pruning of
    PELT, Killick et al. 2012)."""
    m = len(x)
    s0 = np.concatenate([[0.0], np.cumsum(w)])
    s1 = np.concatenate([[0.0], np.cumsum(w * x)])
    s2 = np.concatenate([[0.0], np.cumsum(w * x * x)])
    best = np.full(m + 1, np.inf)
    best[0] = -penalty
    last = np.zeros(m + 1, dtype=int)
    cand = np.array([0])
    for t in range(min_size, m + 1):
        s = cand[cand <= t - min_size]
        if len(s) == 0:
            cand = np.append(cand, t - min_size + 1)
            continue
        cost = s2[t] - s2[s] - (s1[t] - s1[s]) ** 2 / (s0[t] - s0[s])
        total = best[s] + cost + penalty
        k = int(np.argmin(total))
        best[t], last[t] = total[k], s[k]
        keep = best[s] + cost <= best[t]  # PELT: a start that can never win again goes
        cand = np.concatenate([cand[cand > t - min_size], s[keep], [t - min_size + 1]])
        cand = np.unique(cand[cand <= t])
    out, t = [], m
    while t > 0:
        out.append((int(last[t]), t))
        t = last[t]
    return out[::-1]


def _runs(phase: np.ndarray, loud: np.ndarray, n: int, fs: float) -> list[tuple[int, int]]:
    """(first, end) samples of the steps seen by windows of ``n`` samples (detect_steps)."""
    m = len(phase) // n
    w = phase[:m * n].reshape(m, n)
    keep = loud[:m * n].reshape(m, n).all(axis=1)
    tc = (np.arange(n) - (n - 1) / 2) / fs
    wc = w - w.mean(axis=1, keepdims=True)
    slope = wc @ tc / (tc @ tc)
    freq = slope / (2 * np.pi)
    keep &= freq > 0
    # each window's scatter from the phase's residual about its line (white phase noise:
    # var(slope) = var(residual) / sum(tc^2)), relative to its frequency: larger at low
    # frequencies, and for a window across a step, whose phase bends (it weighs little)
    resid = np.mean((wc - np.outer(slope, tc)) ** 2, axis=1) * n / max(n - 2, 1)
    rel = np.sqrt(resid / (tc @ tc)) / np.where(slope > 0, slope, np.inf)
    out = []
    for part in np.split(np.arange(m), np.flatnonzero(np.diff(keep.astype(int))) + 1):
        if not keep[part[0]] or len(part) < 2:
            continue
        logf = np.log(freq[part])
        floor = max(float(np.median(rel[part])) * 0.1, 1e-9)
        weight = 1.0 / np.maximum(rel[part], floor) ** 2
        for a, b in _segments(logf, weight, 8.0 * np.log(max(len(part), 2))):
            out.append([int(part[a]) * n, int(part[b - 1] + 1) * n,
                        float(np.median(logf[a:b]))])
    # a piece far shorter than its neighbours is the analytic signal's transient where the
    # frequency jumps (or noise): it joins the neighbour nearer in frequency
    while len(out) > 1:
        size = np.array([b - a for a, b, _ in out])
        near = [[j for j in (i - 1, i + 1) if 0 <= j < len(out)
                 and out[j][0] - out[i][1] <= n and out[i][0] - out[j][1] <= n]
                for i in range(len(out))]
        short = [i for i in range(len(out)) if near[i]
                 and size[i] < SHORTEST * max(size[j] for j in near[i])]
        if not short:
            break
        i = min(short, key=lambda i: size[i])
        j = min(near[i], key=lambda j: abs(out[j][2] - out[i][2]))
        lo, hi = sorted((i, j))
        out[lo] = [out[lo][0], out[hi][1], out[j][2]]
        out.pop(hi)
    return [(a, b) for a, b, _ in out]


def _line(phase: np.ndarray, t: np.ndarray, a: int, b: int, n: int
          ) -> tuple[np.ndarray, float]:
    """((slope, intercept), standard error of the slope) of the phase line through the
    inner samples of ``[a, b)`` (a window in from either end, where there are three). The
    standard error allows for the residual's correlation: ``var(slope) = s^2 L /
    sum(tc^2)`` with ``L = 1 + 2 sum rho_k`` over the lags where the residual's
    autocorrelation stays positive."""
    inner = slice(a + n, b - n) if b - a > 3 * n else slice(a, b)
    tt, ph = t[inner], phase[inner]
    fit = np.polyfit(tt, ph, 1)
    r = ph - np.polyval(fit, tt)
    var = float(np.mean(r * r))
    if var == 0 or len(r) < 4:
        return fit, 0.0
    acf = np.correlate(r, r, mode="full")[len(r) - 1:len(r) - 1 + min(len(r), 4 * n)] / (
        var * len(r))
    stop = int(np.argmax(acf <= 0)) if np.any(acf <= 0) else len(acf)
    corr = max(1.0, 1.0 + 2.0 * float(np.sum(acf[1:stop])))
    tc = tt - tt.mean()
    return fit, float(np.sqrt(var * corr / (tc @ tc)))


def _lines(runs: list[tuple[int, int]], phase: np.ndarray, t: np.ndarray, n: int
           ) -> tuple[np.ndarray, np.ndarray]:
    """(boundaries, (slope, intercept) per step) of the phase lines through ``runs``
    (:func:`_line`); neighbours whose slopes agree within four standard errors are one
    step; boundaries where consecutive lines meet."""
    runs = list(runs)
    fits = [_line(phase, t, a, b, n) for a, b in runs]

    def join(i):
        runs[i:i + 2] = [(runs[i][0], runs[i + 1][1])]
        fits[i:i + 2] = [_line(phase, t, *runs[i], n)]

    i = 0
    while i + 1 < len(runs):
        (f0, e0), (f1, e1) = fits[i], fits[i + 1]
        if abs(f0[0] - f1[0]) <= max(4 * np.hypot(e0, e1), RESOLUTION * abs(f0[0])):
            join(i)
        else:
            i += 1
    while len(runs) > 1:  # a piece far shorter than a neighbour joins the nearer in slope
        size = [b - a for a, b in runs]
        short = [i for i in range(len(runs)) if size[i] < SHORTEST * max(
            size[j] for j in (i - 1, i + 1) if 0 <= j < len(runs))]
        if not short:
            break
        i = min(short, key=lambda i: size[i])
        j = min((j for j in (i - 1, i + 1) if 0 <= j < len(runs)),
                key=lambda j: abs(fits[j][0][0] - fits[i][0][0]))
        join(min(i, j))
    fits = np.array([f for f, _ in fits])
    bounds = [t[runs[0][0]]]
    for (_, b0), (a1, _), (s0, c0), (s1, c1) in zip(runs[:-1], runs[1:], fits[:-1], fits[1:],
                                                      strict=True):
        meet = (c1 - c0) / (s0 - s1) if s0 != s1 else 0.5 * (t[b0 - 1] + t[a1])
        bounds.append(float(np.clip(meet, t[max(b0 - n, 0)], t[min(a1 + n, len(t) - 1)])))
    bounds.append(t[runs[-1][1] - 1] + (t[1] - t[0]))
    return np.array(bounds), fits


def _score(phase: np.ndarray, t: np.ndarray, loud: np.ndarray, bounds: np.ndarray,
           fits: np.ndarray) -> float:
    """Bayesian information criterion of the piecewise-linear phase ``fits`` over the loud
    samples (two parameters per step and one per boundary)."""
    idx = np.flatnonzero(loud)
    k = np.clip(np.searchsorted(bounds, t[idx], side="right") - 1, 0, len(fits) - 1)
    r = phase[idx] - (fits[k, 0] * t[idx] + fits[k, 1])
    n = len(idx)
    return float(n * np.log(max(np.mean(r * r), 1e-300)) + (3 * len(fits) - 1) * np.log(n))


def detect_steps(x: np.ndarray, fs: float, band: tuple[float, float] | None = None,
                 periods: float = 1.0) -> list[Step]:
    """The steps of a recorded stepped-sine excitation ``x``.

    The phase of a stepped sine is continuous and piecewise linear. The record's analytic
    signal (band-passed to ``[band[0] / 2, 2 band[1]]`` when ``band`` is given) gives the
    unwrapped phase; the frequency of each window is the slope of a line through it, and
    the windows' frequencies are split into pieces of constant frequency by optimal
    partitioning (:func:`_segments`, weighted by each window's scatter from the phase's
    residual about its line, penalty ``8 ln m`` for ``m`` windows). Short windows
    see short steps, long ones resolve small frequency steps under noise (a line's slope
    error falls as ``n^-1.5``): windows of ``periods`` periods of the record's lowest
    frequency (whole periods average out the phase's ripple at twice the drive frequency)
    and their doublings up to a sixty-fourth of the record each propose steps; the proposal
    whose piecewise-linear phase has the lowest Bayesian information criterion over the
    record wins (a missed step leaves a bent phase, a spurious one costs its parameters).
    A piece shorter than :data:`SHORTEST` of a neighbour (the analytic signal's
    transient where the frequency jumps) joins its neighbour nearer in frequency, and
    neighbours whose phase lines have the same slope within four standard errors or
    :data:`RESOLUTION` are one step. A step's frequency is the slope of a line through its
    inner samples' phase; a step ends where its line and the next one's meet; the first
    starts with its first window, the last ends with its last.
    """
    y = np.asarray(x, float) - np.median(x)
    if band is not None:  # (not down to ~0 Hz: a high-pass that slow rings at every step)
        y = sosfiltfilt(butter(4, [band[0] / 2, min(2 * band[1], 0.45 * fs)],
                               btype="bandpass", fs=fs, output="sos"), y)
    z = hilbert(y)
    phase = np.unwrap(np.angle(z))
    loud = np.abs(z) > 0.25 * np.max(np.abs(z))
    m = max(2, round(0.005 * fs))  # the phase's rate over 5 ms: coarse, robust
    rate = ((phase[m:] - phase[:-m]) * fs / (2 * np.pi * m))[loud[m:] & loud[:-m]]
    f_low = float(np.percentile(rate, 5)) if len(rate) else 0.0
    if not f_low > 0:
        raise SignalError("no frequency steps found in the excitation (no positive "
                          "frequency)")
    t = np.arange(len(y)) / fs
    n0 = max(8, round(periods / f_low * fs))
    # the analytic signal's phase is distorted for a few periods at the record's ends and
    # where it starts or stops: away from those
    edge = np.ones(2 * n0 + 1)
    loud = np.convolve(np.pad(loud, n0).astype(float), edge, mode="same")[n0:-n0] > 2 * n0
    best = None
    for k in range(12):
        n = n0 * 2**k
        if k and n * 64 > len(y):
            break
        runs = _runs(phase, loud, n, fs)
        if not runs:
            continue
        bounds, fits = _lines(runs, phase, t, n)
        score = _score(phase, t, loud, bounds, fits)
        if best is None or score < best[0]:
            best = (score, bounds, fits)
    if best is None:
        raise SignalError("no frequency steps found in the excitation")
    _, bounds, fits = best
    return [Step(float(bounds[i]), float(bounds[i + 1]), float(f[0] / (2 * np.pi)))
            for i, f in enumerate(fits)]
