"""Amplitude dependence of a measurement against its model: the table over excitation
levels, the signature classes of the discrepancy, and which missing effects they allow.

A linear structure's FRF does not depend on the excitation level; a nonlinear one's does,
and *how* it does is the fingerprint of the nonlinearity (Kerschen, Worden, Vakakis &
Golinval 2006, "Past, present and future of nonlinear system identification in structural
dynamics", MSSP 20, Sect. 3 (detection, characterisation); Worden & Tomlinson 2001,
*Nonlinearity in Structural Dynamics*, Ch. 2-3: FRF distortion, homogeneity, harmonics):

* resonances that move down and damping that grows with level: micro-slip friction, a
  contact that opens (softening);
* resonances that move up with level: a contact that stiffens, a clearance once the motion
  exceeds its gap (hardening);
* even harmonics or a static (DC) shift: an asymmetric restoring force (a one-sided contact,
  a preload);
* a difference that does not change with level is linear: added mass, an extra mode, linear
  damping.

The shipped models are themselves strongly amplitude dependent (contacts, stick-slip), so
what is classified here is the *discrepancy*: the measured trend with level relative to the
model's own trend at the same levels. For each resonance (tracked across levels by nearest
frequency, :func:`track`) the shift ``100 ln(f_measured / f_model)`` (%) and the damping
ratio ``zeta_measured / zeta_model`` per level; for each level the harmonic ratios ``P_k /
P_1`` measured minus model in dB where the measured ratio stands above its noise floor, and
the DC difference in standard errors. Thresholds (:data:`THRESHOLDS`) are set against what
noise alone produces (see there).

:func:`amplitude_table` is the table; :func:`classes` the classes with their evidence;
:func:`allows` tells whether an effect's declared ``signature_classes`` fit what was found
(diagnosis uses it to prune its candidates); :func:`sentences` say it as a test engineer
would; :func:`amplitude_dependence` bundles all of it for ``compare.json``.

(Over the usual 400 lines: the table, the classes with their thresholds and the sentences
share the per-resonance tracking and are read together; split apart, each would reach into
the others' internals.)
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment

from ..effects.base import SIGNATURE_CLASSES

#: largest relative frequency step (|ln f2/f1|) of a resonance between neighbouring levels
#: of the same FRF (measured or model) for it to count as the same resonance
TRACK_TOL = 0.08
#: largest relative distance (mean |ln f_measured/f_model| over the common levels) at which
#: a measured resonance track is paired with a model track
PAIR_TOL = 0.12

#: Decision thresholds (see :func:`classes`), set against what noise alone gives: the quick
#: study's model (0.15 s chirp, 2e-5 s step) against itself plus white noise of 2 % and 5 %
#: of each channel's RMS, levels 0.03, 0.1 and 0.3 N, seeds 1-8 each (16 comparisons). The
#: largest values noise gave, for the resonances that count (clean modes, 10 dB prominent:
#: the 1.5 kHz mode at every level): shift 0.04 %, shift trend 0.07 %, |ln damping ratio|
#: 0.04, damping trend 0.04; half-power shifts (4.2 kHz mode) 0.1 %; usable harmonic ratio
#: differences 0.3 dB; DC 2.6 standard errors; no measured-only resonance, no class. Each
#: threshold is 7x or more above that (tests/measure/test_signatures.py checks a 3x margin
#: on two seeds), and low enough for the effects' discrepancies (1-10 %, 3-20 dB).
THRESHOLDS = {
    # |change of the shift 100 ln(f_meas/f_model)| from the lowest to the highest level (%)
    "shift_trend_pct": 0.5,
    # |shift| at every level for an amplitude-independent frequency difference (%)
    "shift_pct": 0.5,
    # |change of ln(zeta_meas/zeta_model)| from the lowest to the highest level
    "damping_trend": 0.15,
    # |ln(zeta_meas/zeta_model)| at every level for an amplitude-independent damping
    # difference (a 16 % different damping ratio)
    "damping": 0.15,
    # measured minus model P_2/P_1 (dB), where the larger of the two stands floor_db above
    # the measured ratio's noise floor (compare.harmonic_floor, an upper bound)
    "harmonic_db": 3.0,
    "floor_db": 10.0,
    # |DC difference| in standard errors of the measured mean (compare.dc_standard_error)
    "dc_sigma": 6.0,
    # prominence (dB), measured and model, of a resonance at a level for it to count
    # (weaker peaks: a few lines, noise-sensitive)
    "trend_prominence_db": 10.0,
    # prominence (dB), measured and model, at every level for a softening/hardening judged
    # on half-power values where the single-mode fit failed: a dominant peak whose
    # half-power points are its own (at 10-15 dB, where the shaft model's contacts all
    # rattle above 0.3 N, they moved by -1.6 % and +1.1 % at neighbouring modes)
    "half_power_trend_prominence_db": 20.0,
    # prominence (dB) of a measured resonance the model lacks
    "new_peak_prominence_db": 10.0,
}

#: standard deviations of the model's own scatter (:func:`twin_scatter`) that a frequency
#: threshold grows by: two twins give a standard deviation of two degrees of freedom, so
#: the margin is wide
TWIN_SIGMAS = 3.0


# ---- the table ------------------------------------------------------------------------------
def track(peak_lists: Sequence[Sequence[dict]], tol: float = TRACK_TOL
          ) -> list[list[int | None]]:
    """Follow resonances across levels by nearest frequency.

    ``peak_lists[l]`` are the peaks (dicts with ``"frequency"``) at level ``l`` (levels in
    increasing order). Each level's peaks are assigned to the tracks seen so far by a
    minimum-cost matching (``scipy.optimize.linear_sum_assignment``) on ``|ln f / f_track|``
    (``f_track`` the track's frequency at its latest level), within ``tol``; unassigned
    peaks start new tracks. Returns one list per track: the peak's index at each level, or
    ``None`` where the track has no peak.
    """
    tracks: list[list[int | None]] = []
    last: list[float] = []
    for lv, peaks in enumerate(peak_lists):
        fs = [p["frequency"] for p in peaks]
        assigned: dict[int, int] = {}
        if tracks and fs:
            cost = np.array([[abs(math.log(f / ft)) for f in fs] for ft in last])
            big = 1e6
            rows, cols = linear_sum_assignment(np.where(cost <= tol, cost, big))
            assigned = {c: r for r, c in zip(rows, cols, strict=True) if cost[r, c] <= tol}
        for t in tracks:
            t.append(None)
        for j, f in enumerate(fs):
            if j in assigned:
                tracks[assigned[j]][lv] = j
                last[assigned[j]] = f
            else:
                tracks.append([None] * lv + [j])
                last.append(f)
    return tracks


#: a peak within this relative distance of 2x or 3x a stronger peak's frequency is taken
#: for its harmonic image (see :func:`harmonic_images`)
IMAGE_TOL = 0.015


def harmonic_images(peaks: Sequence[dict], tol: float = IMAGE_TOL) -> list[int]:
    """Indices of the peaks that are harmonic images of a stronger one.

    The FRF of a swept record (one segment, ``X(f) / P(f)``) carries, at ``k f_r``, the
    k-th harmonic of the response produced while the sweep passed a strong resonance
    ``f_r``: a peak that no mode makes (it moves with ``f_r`` and grows with level). A peak
    within ``tol`` of 2 or 3 times the frequency of a peak higher than itself is such an
    image and is left out of the tracking (a true mode at exactly that frequency would be
    left out too). Farina's (2000) windowing of the deconvolved impulse response would
    remove the images from the FRF itself."""
    out = []
    for i, p in enumerate(peaks):
        for q in peaks:
            if q["peak_db"] > p["peak_db"] and any(
                    abs(math.log(p["frequency"] / (k * q["frequency"]))) < tol
                    for k in (2, 3)):
                out.append(i)
                break
    return out


def _freqs(peaks: Sequence[Sequence[dict]], t: list[int | None]) -> list[float | None]:
    return [None if i is None else peaks[lv][i]["frequency"] for lv, i in enumerate(t)]


def pair_tracks(meas: list[list[int | None]], model: list[list[int | None]],
                peaks_meas, peaks_model, tol: float = PAIR_TOL) -> list[tuple]:
    """Pair measured and model tracks by a minimum-cost matching
    (``linear_sum_assignment``). The cost of a pair is its mean distance over the levels
    where either track has a peak: ``|ln f_meas / f_model|`` where both have one, ``tol``
    where only one has (so a track is paired with the one that follows it over the same
    levels rather than with a nearer one seen at one level only). Pairs need a common level
    and a cost within ``tol``. Returns ``(i, j)`` index pairs, ``None`` for an unpaired
    side."""
    fm = [_freqs(peaks_meas, t) for t in meas]
    fs = [_freqs(peaks_model, t) for t in model]
    cost = np.full((len(fm), len(fs)), np.inf)
    for i, a in enumerate(fm):
        for j, b in enumerate(fs):
            d = [abs(math.log(x / y)) if x is not None and y is not None else tol
                 for x, y in zip(a, b, strict=True) if x is not None or y is not None]
            common = sum(x is not None and y is not None for x, y in zip(a, b, strict=True))
            if common:
                cost[i, j] = float(np.mean(d))
    pairs, used_i, used_j = [], set(), set()
    if cost.size:
        rows, cols = linear_sum_assignment(np.where(cost <= tol, cost, 1e6))
        for r, c in zip(rows, cols, strict=True):
            if cost[r, c] <= tol:
                pairs.append((int(r), int(c)))
                used_i.add(int(r))
                used_j.add(int(c))
    pairs += [(i, None) for i in range(len(fm)) if i not in used_i]
    pairs += [(None, j) for j in range(len(fs)) if j not in used_j]
    return pairs


def _values(p: dict | None, q: dict | None) -> tuple:
    """(f_p, zeta_p, f_q, zeta_q, method) of two peaks (either may be missing): the
    single-mode fits where every present peak has one, else the half-power values (never a
    fit on one side and a half-power value on the other)."""
    present = [x for x in (p, q) if x is not None]
    fit = bool(present) and all(x.get("fit_frequency") for x in present)

    def get(x):
        if x is None:
            return None, None
        return (x["fit_frequency"], x["fit_damping"]) if fit else \
            (x["frequency"], x["damping_ratio"])

    return (*get(p), *get(q), "mode fit" if fit else "half-power")


def twin_scatter(peak: dict | None, twins: Sequence[Sequence[dict]], method: str | None
                 ) -> float | None:
    """The model's own scatter (%) of ``peak``'s frequency from its twin runs
    (:func:`sensfw.measure.compare.twin_drive`; ``twins``: their peaks): ``100 sqrt(2)``
    times the standard deviation of ``ln f`` over the model and the twins' nearest peaks
    (by the same ``method``'s frequencies), i.e. the standard deviation of the difference
    of two realisations, as a measured-minus-model shift is; infinite where a twin has no
    peak within :data:`TRACK_TOL` (the model does not determine the peak); ``None``
    without twins."""
    if peak is None or not twins:
        return None
    key = "fit_frequency" if method == "mode fit" else "frequency"
    f = peak.get(key) or peak["frequency"]
    logs = [math.log(f)]
    for peaks in twins:
        d = [math.log(q.get(key) or q["frequency"]) for q in peaks]
        if not d or min(abs(x - logs[0]) for x in d) > TRACK_TOL:
            return math.inf
        logs.append(min(d, key=lambda x: abs(x - logs[0])))
    return float(100 * math.sqrt(2) * np.std(logs, ddof=1))


def _twin_peak(peak: dict | None, twins: Sequence[Sequence[dict]]) -> float | None:
    """The frequency of the nearest peak, within :data:`PAIR_TOL`, that one of the model's
    twin runs has at a measured ``peak`` the model itself lacks (``None`` if none has): the
    model's own realisations can show it, so it is no evidence of a missing mode."""
    if peak is None:
        return None
    near = [q["frequency"] for peaks in twins for q in peaks
            if abs(math.log(q["frequency"] / peak["frequency"])) <= PAIR_TOL]
    return min(near, key=lambda f: abs(math.log(f / peak["frequency"])), default=None)


def amplitude_table(levels: Sequence) -> dict:
    """The amplitude-dependence table of model/measurement comparisons at several levels.

    ``levels`` are :class:`~sensfw.measure.compare.LevelComparison` objects (or anything
    with ``level``, ``peaks_measured``, ``peaks_model``, ``harmonics``, ``thd_measured``,
    ``thd_model``, ``dc_measured``, ``dc_model``). Returns ``{"levels", "resonances",
    "harmonics"}``: per resonance track (measured and model tracks paired,
    :func:`track`, :func:`pair_tracks`) one row per level with frequency and damping ratio
    measured and model, the shift ``100 ln(f_meas/f_model)`` (%) and the damping ratio
    ``zeta_meas/zeta_model``; per level H2/H1, H3/H1 (with the measured noise floor), THD
    and DC, measured and model.
    """
    levels = sorted(levels, key=lambda c: c.level)

    def modes(peaks):
        drop = set(harmonic_images(peaks))
        return [p for i, p in enumerate(peaks) if i not in drop]

    # the FRF's line spacing (what a half-power frequency is known to)
    line = [float(np.median(np.diff(c.f))) if len(getattr(c, "f", ())) > 1 else 0.0
            for c in levels]
    pm = [modes(c.peaks_measured) for c in levels]
    px = [modes(c.peaks_model) for c in levels]
    pt = [[modes(t) for t in getattr(c, "peaks_twins", ())] for c in levels]
    tm, tx = track(pm), track(px)
    rows = []
    for i, j in pair_tracks(tm, tx, pm, px):
        per = []
        for lv, c in enumerate(levels):
            a = pm[lv][tm[i][lv]] if i is not None and tm[i][lv] is not None else None
            b = px[lv][tx[j][lv]] if j is not None and tx[j][lv] is not None else None
            fa, za, fb, zb, method = _values(a, b)
            both = a is not None and b is not None
            per.append({
                "level": c.level, "measured_hz": fa, "model_hz": fb,
                "measured_damping": za, "model_damping": zb,
                "measured_db": a["peak_db"] if a else None,
                "model_db": b["peak_db"] if b else None,
                "measured_prominence_db": a["prominence_db"] if a else None,
                "model_prominence_db": b["prominence_db"] if b else None,
                "shift_pct": 100 * math.log(fa / fb) if both else None,
                # the same from the half-power frequencies whatever the method (a trend
                # across levels must not mix single-mode fits and half-power values)
                "half_power_shift_pct": 100 * math.log(a["frequency"] / b["frequency"])
                if both else None,
                "line_hz": line[lv],
                "damping_ratio": za / zb if both and za and zb else None,
                "method": method if (a or b) else None,
                "model_scatter_pct": twin_scatter(b, pt[lv], method),
                "twin_peak_hz": _twin_peak(a, pt[lv]) if b is None else None})
        kind = "paired" if i is not None and j is not None else \
            "measured only" if i is not None else "model only"
        ref = next(r["measured_hz"] or r["model_hz"] for r in per
                   if r["measured_hz"] or r["model_hz"])
        rows.append({"frequency_hz": ref, "kind": kind, "levels": per})
    rows.sort(key=lambda r: r["frequency_hz"])
    for n, r in enumerate(rows):
        r["id"] = f"R{n + 1}"
    harm = []
    for c in levels:
        h = {r["order"]: r for r in c.harmonics}
        row = {"level": c.level, "thd_measured": c.thd_measured, "thd_model": c.thd_model,
               "dc_measured": c.dc_measured, "dc_model": c.dc_model,
               "dc_standard_error": getattr(c, "dc_standard_error", None)}
        for k in (2, 3):
            r = h.get(k, {})
            row[f"h{k}_measured"] = r.get("measured_ratio")
            row[f"h{k}_model"] = r.get("model_ratio")
            row[f"h{k}_floor"] = r.get("measured_floor_ratio")
        harm.append(row)
    return {"levels": [c.level for c in levels],
            "unit": getattr(levels[0], "unit", "N") if levels else "N",
            "resonances": rows, "harmonics": harm}


# ---- the classes ----------------------------------------------------------------------------
def _trends(table: dict, th: dict, fit: bool = True, half_power: bool = False
            ) -> list[dict]:
    """Per paired resonance present on both sides at two levels or more (``prominence``
    ``trend_prominence_db`` on both): the shifts and damping ratios per level, their change
    from the lowest to the highest such level and the least-squares slope of the shift
    against log10(level). ``fit``: only levels where both sides are clean modes (single-mode
    fits); else the resonances with fewer than two such levels, on their values (half-power
    ones where the fit failed: frequencies on the FRF's lines, damping ratios biased; see
    :func:`classes`), or with ``half_power`` on their half-power shifts at every level."""
    out = []
    for r in table["resonances"]:
        if r["kind"] != "paired":
            continue
        rows = [x for x in r["levels"] if x["shift_pct"] is not None
                and min(x["measured_prominence_db"], x["model_prominence_db"])
                >= th["trend_prominence_db"]]
        fitted = [x for x in rows if x["method"] == "mode fit"]
        if fit:
            rows = fitted
        elif len(fitted) >= 2:
            continue
        if len(rows) < 2:
            continue
        lv = np.array([x["level"] for x in rows])
        s = np.array([x["half_power_shift_pct" if half_power else "shift_pct"]
                      for x in rows])
        g = np.array([math.log(x["damping_ratio"]) if x["damping_ratio"] else np.nan
                      for x in rows])
        slope = float(np.polyfit(np.log10(lv), s, 1)[0]) if len(set(lv)) > 1 else 0.0
        gd = g[np.isfinite(g)]
        line = max(x.get("line_hz") or 0.0 for x in rows)
        twin = max(x.get("model_scatter_pct") or 0.0 for x in rows)
        out.append({
            "resonance": r["id"], "frequency_hz": r["frequency_hz"],
            "levels": lv.tolist(), "shift_pct": s.tolist(),
            "damping_ratio": [x["damping_ratio"] for x in rows],
            "shift_trend_pct": float(s[-1] - s[0]),
            "shift_slope_pct_per_decade": slope,
            "damping_trend": float(gd[-1] - gd[0]) if len(gd) >= 2 else None,
            "prominence_db": float(min(min(x["measured_prominence_db"],
                                           x["model_prominence_db"]) for x in rows)),
            "method": "mode fit" if fit else "half-power",
            # half-power frequencies sit on the FRF's lines: a shift is known to one line
            "line_pct": 0.0 if fit else 100 * line / r["frequency_hz"],
            # the model's own scatter of the shift at its worst level (its twin runs)
            "model_scatter_pct": twin})
    return out


def _harmonic_differences(table: dict, th: dict) -> list[dict]:
    """Per level and order: measured minus model ``P_k/P_1`` (dB) where the larger of the
    two stands ``floor_db`` above the measured ratio's noise floor."""
    out = []
    margin = 10 ** (th["floor_db"] / 20)
    for h in table["harmonics"]:
        for k in (2, 3):
            m, s, fl = h[f"h{k}_measured"], h[f"h{k}_model"], h[f"h{k}_floor"]
            if not (m and s):
                continue
            usable = fl is None or max(m, s) >= margin * fl
            out.append({"level": h["level"], "order": k, "measured": m, "model": s,
                        "floor": fl, "difference_db": 20 * math.log10(m / s),
                        "usable": bool(usable)})
    return out


def classes(levels: Sequence, thresholds: dict | None = None, table: dict | None = None
            ) -> dict[str, dict]:
    """Signature classes (:data:`~sensfw.effects.base.SIGNATURE_CLASSES`) of the
    discrepancy between measurement and model over several levels, each with its evidence.

    ``levels``: comparisons at two levels or more (:func:`amplitude_table`); with fewer,
    no class (one level says nothing about amplitude dependence). A class holds when
    (thresholds in :data:`THRESHOLDS`):

    * ``softening`` / ``hardening``: a resonance that is a clean mode on both sides
      (single-mode fits, ``trend_prominence_db`` prominent) at two levels or more and whose
      shift ``100 ln(f_meas/f_model)`` falls / rises by more than ``shift_trend_pct`` from
      the lowest to the highest of them (the damping ratio's trend is part of the
      evidence); or, where the fit fails at all but one level, a resonance
      ``half_power_trend_prominence_db`` prominent whose half-power shift does so by more
      than ``shift_trend_pct`` plus two FRF lines;
    * ``amplitude_independent``: such a resonance whose shift stays beyond ``shift_pct``
      (same sign at every level) or whose damping ratio stays beyond ``exp(+-damping)``
      while neither changes by more than its trend threshold; or a prominent resonance
      without clean fits whose half-power frequencies do so with one FRF line
      (``1/T``) added to both frequency thresholds (its damping is not judged);
    * ``even_harmonics``: ``P_2/P_1`` measured above the model's by more than
      ``harmonic_db`` at a level where it stands above the noise floor, or a DC
      difference beyond ``dc_sigma`` standard errors;
    * ``new_peak``: a measured resonance no model resonance pairs with, at least
      ``new_peak_prominence_db`` prominent.

    Where the levels carry the model's twin runs, every frequency threshold grows by
    :data:`TWIN_SIGMAS` standard deviations of the model's own scatter of that shift
    (``model_scatter_pct``; of a trend, ``sqrt(2)`` times it): a shift the model does not
    determine is no evidence. Nor is a new peak that a twin shows (``twin_peak_hz``), or one
    at a level where a twin lost one of the model's peaks.

    Several classes may hold at once. Returns ``{class: evidence}``. ``table``: the
    :func:`amplitude_table` of ``levels`` if already built.
    """
    th = {**THRESHOLDS, **(thresholds or {})}
    levels = sorted(levels, key=lambda c: c.level)
    if len({c.level for c in levels}) < 2:
        return {}
    table = table or amplitude_table(levels)
    found: dict[str, dict] = {}
    trends = _trends(table, th)
    # a shift the model's twins move is no evidence: a level's shift has the standard
    # deviation model_scatter_pct, a trend (two levels) sqrt(2) times it; three of them
    # (infinite where a twin lost the peak)
    soft = [t for t in trends
            if t["shift_trend_pct"] < -(th["shift_trend_pct"] + TWIN_SIGMAS * math.sqrt(2)
                                        * t["model_scatter_pct"])]
    hard = [t for t in trends
            if t["shift_trend_pct"] > th["shift_trend_pct"] + TWIN_SIGMAS * math.sqrt(2)
            * t["model_scatter_pct"]]
    # a resonance whose nonlinearity spoils the single-mode fit at a level (a hardening
    # peak bends and jumps under a sweep): its half-power shifts, each known to one FRF
    # line on either side, so a trend to two lines
    for t in _trends(table, th, fit=False, half_power=True):
        if t["prominence_db"] < th["half_power_trend_prominence_db"]:
            continue
        margin = th["shift_trend_pct"] + 2 * t["line_pct"] + \
            TWIN_SIGMAS * math.sqrt(2) * t["model_scatter_pct"]
        if t["shift_trend_pct"] > margin:
            hard.append(t)
        elif t["shift_trend_pct"] < -margin:
            soft.append(t)
    if soft:
        found["softening"] = {"resonances": soft}
    if hard:
        found["hardening"] = {"resonances": hard}
    flat = []
    for t in trends + _trends(table, th, fit=False):
        q, fit = t["line_pct"] + TWIN_SIGMAS * t["model_scatter_pct"], \
            t["method"] == "mode fit"
        if abs(t["shift_trend_pct"]) > th["shift_trend_pct"] + q or \
                (fit and t["damping_trend"] is not None and
                 abs(t["damping_trend"]) > th["damping_trend"]):
            continue
        s = np.array(t["shift_pct"])
        g = np.log([d for d in t["damping_ratio"] if d])
        shifted = bool(np.all(np.abs(s) > th["shift_pct"] + q)
                       and abs(np.sign(s).sum()) == len(s))
        # half-power damping ratios of a smoothed FRF say little (see sensfw.signal.modal)
        damped = bool(fit and len(g) == len(s) and np.all(np.abs(g) > th["damping"])
                      and abs(np.sign(g).sum()) == len(g))
        if shifted or damped:
            flat.append({**t, "frequency_differs": shifted, "damping_differs": damped})
    if flat:
        found["amplitude_independent"] = {"resonances": flat}
    harm = _harmonic_differences(table, th)
    # even harmonics the model lacks: P2/P1 above the model's, and the even/odd balance
    # moved towards the even orders. For a weak nonlinearity scaled by a factor a, an
    # asymmetric (quadratic) term gives P2 ~ a and, through its cascade, P3 ~ a^2, a
    # symmetric (cubic) one P3 ~ a and no P2 (Worden & Tomlinson 2001, Ch. 3; Volterra
    # series): an asymmetric change has d2 >= d3 / 2 (dB), a symmetric one d2 << d3 / 2.
    # An effect that only makes the response more nonlinear overall (an added mass moving
    # a resonance into the model's own nonlinear range) raises P3 faster than P2.
    odd = {h["level"]: h for h in harm if h["order"] == 3 and h["usable"]}
    even = [{**h, "odd_difference_db": odd[h["level"]]["difference_db"]
             if h["level"] in odd else None}
            for h in harm if h["order"] == 2 and h["usable"]
            and h["difference_db"] > th["harmonic_db"]
            and (h["level"] not in odd
                 or h["difference_db"] >= odd[h["level"]]["difference_db"] / 2)]
    dc = []
    for h in table["harmonics"]:
        se = h["dc_standard_error"]
        if se and abs(h["dc_measured"] - h["dc_model"]) > th["dc_sigma"] * se:
            dc.append({"level": h["level"], "measured": h["dc_measured"],
                       "model": h["dc_model"],
                       "sigma": (h["dc_measured"] - h["dc_model"]) / se})
    if even or dc:
        found["even_harmonics"] = {"harmonics": even, "dc": dc}
    # levels where a twin lost one of the model's peaks: the model's peaks there are not
    # determined by its drive, so a measured peak it lacks says nothing
    lost = {x["level"] for r in table["resonances"] for x in r["levels"]
            if x.get("model_scatter_pct") == math.inf}
    new = []
    for r in table["resonances"]:
        if r["kind"] != "measured only":
            continue
        rows = [x for x in r["levels"] if x["measured_hz"] is not None
                and x["measured_prominence_db"] >= th["new_peak_prominence_db"]
                and x.get("twin_peak_hz") is None and x["level"] not in lost]
        if rows:
            new.append({"resonance": r["id"], "frequency_hz": r["frequency_hz"],
                        "levels": [x["level"] for x in rows],
                        "prominence_db": max(x["measured_prominence_db"] for x in rows)})
    if new:
        found["new_peak"] = {"resonances": new}
    return {k: found[k] for k in SIGNATURE_CLASSES if k in found}


def allows(effect, found: dict) -> bool:
    """Whether a candidate effect fits the signature classes ``found`` (:func:`classes`).

    ``effect`` is an :class:`~sensfw.effects.Effect` class or instance or a registered
    name. Everything is allowed when nothing was found (one level, or no discrepancy that
    changes with level beyond noise: nothing to prune on) and an effect that declares no
    ``signature_classes`` is always allowed; otherwise the effect needs a declared class
    among those found, and ``new_peak`` alone rules nothing out: it is evidence *for* an
    extra mode but not *against* the rest. A measured resonance without a model partner is
    also what any effect that moves a resonance past :data:`PAIR_TOL`, splits one or
    makes one show leaves (read off a poorly fitting model): in ``bench/recovery.py`` a
    friction at bearing l1 that sticks moved the 2.0 kHz mode to 1.67 kHz (seed 2060) or
    showed a 4.3 kHz resonance the model has none of (seed 2051), and a hardening at slide
    bearing 2 split the 1.78 kHz mode into 1.66 and 1.79 kHz (seed 2031), each found as
    ``new_peak`` alone, which left the flexible modes only.
    """
    if not found:
        return True
    if isinstance(effect, str):
        from ..plugins import effects

        effect = effects.get(effect)
    declared = set(getattr(effect, "signature_classes", ()) or ())
    return not declared or bool(declared & set(found)) or not set(found) - {"new_peak"}


# ---- in words -------------------------------------------------------------------------------
_CAUSES = {
    "softening": "the signature of micro-slip friction or of a contact that opens",
    "hardening": "the signature of a contact that stiffens or of a clearance the motion "
                 "has crossed",
    "amplitude_independent": "a linear difference (added mass, an extra mode, linear "
                             "damping)",
    "even_harmonics": "the signature of an asymmetric contact or a preload",
    "new_peak": "an extra mode, or a resonance an effect moved or split beyond pairing",
}


def _khz(f: float) -> str:
    return f"{f / 1e3:.3g} kHz" if f >= 1e3 else f"{f:.0f} Hz"


def _lv(x: float, unit: str) -> str:
    return f"{x:.3g} {unit}"


def _resonance_sentence(cls: str, t: dict, unit: str, th: dict) -> str:
    s, d, lv = t["shift_pct"], t["damping_ratio"], t["levels"]

    def rel(v):
        return f"{abs(v):.1f} % {'above' if v >= 0 else 'below'}"

    steady = t["damping_trend"] is None or abs(t["damping_trend"]) <= th["damping_trend"]
    if not (d[0] and d[-1]) or t["method"] != "mode fit":  # half-power damping: biased
        damp = ""
    elif steady:
        damp = f"its damping stays {np.exp(np.mean(np.log(d))):.1f}x the model's"
    else:
        damp = f"its damping going from {d[0]:.1f}x to {d[-1]:.1f}x the model's"
    span = f"{_lv(lv[0], unit)} to {_lv(lv[-1], unit)}"
    if cls == "amplitude_independent":
        damp = damp.replace("its damping stays", "with").replace("model's", "model's damping")
        damp = damp.replace("its damping going from", "with damping from")
        return (f"The {_khz(t['frequency_hz'])} resonance stays {rel(np.mean(s))} the "
                f"model's{' ' + damp if damp else ''} at every level from {span}: amplitude "
                f"independent, {_CAUSES[cls]} (Worden & Tomlinson 2001).")
    word = cls
    if cls == "softening" and not steady and t["damping_trend"] > 0:
        word += " with growing damping"
    elif cls == "softening" and d[0] and d[-1] and min(d[0], d[-1]) > math.exp(th["damping"]):
        word += " with added damping"
    force = "force" if unit == "N" else "excitation"
    damp = damp.replace("its damping going", "its damping goes")
    return (f"The {_khz(t['frequency_hz'])} resonance moves from {rel(s[0])} to {rel(s[-1])} "
            f"the model's{' while ' + damp if damp else ''} as the {force} rises from {span}: "
            f"{word}, {_CAUSES[cls]} (Kerschen et al. 2006).")


def sentences(found: dict, table: dict, thresholds: dict | None = None) -> list[str]:
    """One sentence per class found, as a test engineer would write it in a report."""
    th = {**THRESHOLDS, **(thresholds or {})}
    unit = table.get("unit", "N")
    lv = table["levels"]
    if len(set(lv)) < 2:  # also two records of one level (a sweep and its FRF), as classes
        return ["One excitation level: the amplitude dependence needs two or more."]
    if not found:
        return [f"Between {_lv(lv[0], unit)} and {_lv(lv[-1], unit)} the differences "
                "between measurement and model do not change with level beyond what noise "
                "gives, and no resonance or harmonic differs in an amplitude-independent way "
                "beyond it: no signature of a missing effect."]
    out = []
    order = ("softening", "hardening", "even_harmonics", "amplitude_independent", "new_peak")
    for cls, ev in sorted(found.items(), key=lambda kv: order.index(kv[0])):
        if cls in ("softening", "hardening", "amplitude_independent"):
            t = max(ev["resonances"], key=lambda r: (r["prominence_db"],
                                                     abs(r["shift_trend_pct"])))
            out.append(_resonance_sentence(cls, t, unit, th))
        elif cls == "even_harmonics":
            parts = []
            if ev["harmonics"]:
                h = max(ev["harmonics"], key=lambda h: h["difference_db"])
                odd = "" if h["odd_difference_db"] is None else \
                    f" (H3/H1 {h['odd_difference_db']:+.1f} dB)"
                parts.append(f"H2/H1 is {h['difference_db']:.1f} dB above the model's at "
                             f"{_lv(h['level'], unit)}{odd}")
            if ev["dc"]:
                d = max(ev["dc"], key=lambda d: abs(d["sigma"]))
                parts.append(f"the mean response differs from the model's by "
                             f"{d['sigma']:+.0f} standard errors at {_lv(d['level'], unit)}")
            out.append(" and ".join(parts).capitalize()[0] + " and ".join(parts)[1:] +
                       f": even harmonics the model lacks, {_CAUSES[cls]} "
                       "(Worden & Tomlinson 2001).")
        elif cls == "new_peak":
            r = max(ev["resonances"], key=lambda r: r["prominence_db"])
            at = ", ".join(_lv(x, unit) for x in r["levels"])
            out.append(f"A resonance at {_khz(r['frequency_hz'])} ({r['prominence_db']:.0f} dB "
                       f"prominent at {at}) has no counterpart in the model: a new peak, "
                       f"{_CAUSES[cls]}.")
    return out


def amplitude_dependence(levels: Sequence, thresholds: dict | None = None) -> dict:
    """Everything ``compare.json`` and the report say about the levels: the table
    (:func:`amplitude_table`), the classes with their evidence (:func:`classes`), the
    sentences, the THD growth and the thresholds used."""
    levels = sorted(levels, key=lambda c: c.level)
    if not levels:
        raise ValueError("amplitude_dependence needs at least one level")
    th = {**THRESHOLDS, **(thresholds or {})}
    table = amplitude_table(levels)
    found = classes(levels, th, table)
    out = {"levels": table["levels"], "table": table, "classes": found,
           "sentences": sentences(found, table, th), "thresholds": th}
    lo, hi = levels[0], levels[-1]
    out["thd_ratio"] = {
        "measured": hi.thd_measured / lo.thd_measured
        if len(levels) > 1 and lo.thd_measured else None,
        "model": hi.thd_model / lo.thd_model if len(levels) > 1 and lo.thd_model else None}
    summary = []
    r = out["thd_ratio"]["measured"]
    if r:
        summary.append(f"measured THD grows {r:.2f}x for a {hi.level / lo.level:.2f}x level"
                       + (": nonlinear" if r > 1.3 else ""))
    out["summary"] = summary + out["sentences"]
    return out
