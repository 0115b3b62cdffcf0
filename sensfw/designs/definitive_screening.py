"""Definitive screening designs (Jones & Nachtsheim 2011, J. Quality Technology 43(1):1-15),
built from conference matrices (Xiao, Lin & Bai 2012, J. Quality Technology 44(1):2-8).

With a conference matrix ``C`` of order ``m`` (zero diagonal, +-1 elsewhere,
``C^T C = (m - 1) I``) the design ``[C; -C; 0]`` has ``2m + 1`` runs at three levels. The
fold-over makes every main-effect column orthogonal to every two-factor interaction and to
every quadratic column, and the zeros let each quadratic effect be estimated: one stage
screens main effects and curvature (the paper needs two: OAT then a 3^k factorial).

Conference matrices here come from Paley's construction for every odd prime ``q``
(``m = q + 1``: symmetric for q = 1 mod 4, skew for q = 3 mod 4), giving m = 4, 6, 8, 12, 14,
18, 20, 24, 30, 32, ...; k variables use the smallest such m >= k (m = k for even k of that
list: 2k + 1 runs) and the first k columns.
"""

from __future__ import annotations

from typing import Annotated

import numpy as np
import pandas as pd
from pydantic import Field
from scipy import stats

from ..options import Float, Int, PluginOptions
from ..plugins import designs
from ._coded import to_table
from .base import ROUND_OFF, Design, DesignError, ScreeningResult, relative, responses


def _is_prime(n: int) -> bool:
    return n > 1 and all(n % d for d in range(2, int(n**0.5) + 1))


def conference_matrix(m: int) -> np.ndarray:
    """A conference matrix of order ``m = q + 1`` (q an odd prime), Paley construction."""
    q = m - 1
    if not (_is_prime(q) and q > 2):
        raise DesignError(f"no Paley conference matrix of order {m} (m - 1 must be an odd "
                          "prime)")
    residues = {(i * i) % q for i in range(1, q)}
    chi = np.array([0] + [1 if i in residues else -1 for i in range(1, q)])
    Q = np.array([[chi[(j - i) % q] for j in range(q)] for i in range(q)])
    C = np.zeros((m, m), dtype=int)
    C[0, 1:] = 1
    C[1:, 0] = 1 if q % 4 == 1 else -1
    C[1:, 1:] = Q
    if not np.array_equal(C.T @ C, (m - 1) * np.eye(m, dtype=int)):
        raise DesignError(f"conference matrix of order {m} failed its check")  # pragma: no cover
    return C


def order_for(k: int) -> int:
    m = max(k, 4)
    while not _is_prime(m - 1) or m - 1 < 3:
        m += 1
    return m


def dsd_matrix(k: int) -> np.ndarray:
    """Coded (-1, 0, +1) definitive screening design for k factors."""
    C = conference_matrix(order_for(k))[:, :k]
    return np.vstack([C, -C, np.zeros((1, k), dtype=int)]).astype(float)


@designs.register("definitive_screening")
class DefinitiveScreening(Design):
    """Definitive screening design (see module docstring); ``2m + 1`` runs.

    Analysis: main effects by least squares (orthogonal, so each is estimated free of
    two-factor interactions and quadratics); then quadratic terms enter one by one (forward
    selection, t-test with a Bonferroni level ``alpha / (number of candidate terms)``) to
    flag curvature; active main effects are those significant in the final model with
    Holm's step-down correction at family-wise level ``alpha`` (k tests on few residual
    degrees of freedom would otherwise flag spurious effects). Importance = |main effect|.
    """

    name = "definitive_screening"

    class Options(PluginOptions):
        alpha: Annotated[Float, Field(gt=0, lt=0.5)] = Field(
            0.05, description="a number in (0, 0.5)")
        extra_center: Annotated[Int, Field(ge=0)] = Field(0, description="an integer >= 0")

    def n_runs(self, space):
        return 2 * order_for(len(space)) + 1 + self.options["extra_center"]

    def generate(self, space, seed=None):
        X = dsd_matrix(len(space))
        if self.options["extra_center"]:
            X = np.vstack([X, np.zeros((self.options["extra_center"], X.shape[1]))])
        return to_table(space, X, "dsd")

    def analyze(self, space, table, y) -> ScreeningResult:
        y = responses(table, y, self.name)
        ok = np.isfinite(y)
        Z = np.round(space.code(table).to_numpy()[ok], 12)
        yy = y[ok]
        k = Z.shape[1]
        alpha = float(self.options["alpha"])
        quads: list[int] = []

        def fit(q):
            A = np.column_stack([np.ones(len(yy)), Z, *[Z[:, j] ** 2 for j in q]])
            coef, *_ = np.linalg.lstsq(A, yy, rcond=None)
            resid = yy - A @ coef
            dof = len(yy) - A.shape[1]
            if dof <= 0:
                return coef, None, dof
            s2 = resid @ resid / dof
            cov = s2 * np.linalg.pinv(A.T @ A)
            return coef, np.sqrt(np.diag(cov)), dof

        flat = np.ptp(yy) <= ROUND_OFF * np.max(np.abs(yy))  # effects and SEs are round-off
        while not flat:  # forward selection of quadratic terms (Bonferroni over candidates)
            coef, se, dof = fit(quads)
            best, best_p = None, alpha / max(k - len(quads), 1)
            for j in range(k):
                if j in quads:
                    continue
                c2, se2, dof2 = fit([*quads, j])
                if se2 is None or dof2 < 1:
                    continue
                t = c2[-1] / se2[-1] if se2[-1] > 0 else np.inf
                p = 2 * stats.t.sf(abs(t), dof2)
                if p < best_p:
                    best, best_p = j, p
            if best is None:
                break
            quads.append(best)
        coef, se, dof = fit(quads)
        main = coef[1:k + 1]
        if se is not None and dof > 0 and not flat:
            with np.errstate(divide="ignore", invalid="ignore"):
                p_main = 2 * stats.t.sf(np.abs(main / se[1:k + 1]), dof)
        else:
            p_main = np.full(k, np.nan)
        quad = np.zeros(k)
        for i, j in enumerate(quads):
            quad[j] = coef[k + 1 + i]
        active = np.zeros(k, bool)  # Holm step-down at family-wise level alpha
        for rank, j in enumerate(np.argsort(p_main)):
            if not p_main[j] < alpha / (k - rank):
                break
            active[j] = True
        tab = pd.DataFrame({"variable": space.names, "main_effect": main, "p": p_main,
                            "active": active, "quadratic": quad,
                            "curvature": [j in quads for j in range(k)]}).set_index("variable")
        notes = [f"conference matrix of order {order_for(k)}; {dof} residual degrees of "
                 "freedom"]
        if quads:
            notes.append("curvature: quadratic effect of " +
                         ", ".join(space.names[j] for j in quads))
        if not ok.all():
            notes.append(f"{(~ok).sum()} failed runs left out; orthogonality is lost")
        imp = relative(tab["main_effect"].abs(), y, notes)
        return ScreeningResult(importance=imp, table=tab, notes=notes)
