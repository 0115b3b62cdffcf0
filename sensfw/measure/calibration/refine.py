"""The local phase of a calibration: least squares on the residual vector from the best
points of the global phase, with the simulations themselves.

``"dfols"`` (default): DFO-LS (Cartis, Fiala, Marteau & Roberts 2019), a derivative-free
trust-region Gauss-Newton method that keeps an interpolation set of past evaluations and
replaces one point of it per iteration, so each step costs about one simulation instead of
a fresh finite-difference Jacobian of ``d``. Its evaluations are sequential; two starts are
solved at once in threads whose requests are gathered into batches of parallel runs
(:class:`Batcher`), so both workers stay busy.

``"lm"``: the bounded finite-difference Levenberg-Marquardt this project used before
(:func:`levenberg_marquardt`), kept as the baseline of ``bench/recovery.py``.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence

import numpy as np

Log = Callable[[str], None]
#: Evaluate coded points: list of z -> list of weighted residual vectors (None: failed)
EvaluateCoded = Callable[[list[np.ndarray]], list[np.ndarray | None]]


class Batcher:
    """Gathers the one-point requests of ``clients`` solver threads into batches: the
    serving thread runs a batch once every live client waits for a result, in the order of
    the clients (not of their arrival, which the threads' timing decides: the runs' order
    is the order of every trial after them, and so of the surrogates fitted to them; in
    arrival order, two calibrations of the same case could differ)."""

    def __init__(self, evaluate: EvaluateCoded, clients: int):
        self.evaluate = evaluate
        self.cond = threading.Condition()
        self.pending: list[tuple[np.ndarray, dict]] = []
        self.alive = clients
        #: a KeyboardInterrupt (or SystemExit) met while evaluating: every later request
        #: gets it at once, and :func:`dfols_solves` raises it once the solvers have left
        self.interrupted: BaseException | None = None

    def __call__(self, z: np.ndarray, client: int = 0) -> np.ndarray | None:
        slot: dict = {"done": threading.Event(), "client": client}
        with self.cond:
            self.pending.append((np.array(z, float), slot))
            self.cond.notify_all()
        slot["done"].wait()
        if "error" in slot:
            raise slot["error"]
        return slot["w"]

    def leave(self) -> None:
        with self.cond:
            self.alive -= 1
            self.cond.notify_all()

    def serve(self) -> None:
        while True:
            with self.cond:
                self.cond.wait_for(lambda: self.alive == 0 or
                                   len(self.pending) >= self.alive)
                if not self.pending and self.alive == 0:
                    return
                batch, self.pending = self.pending, []
            batch.sort(key=lambda zs: zs[1]["client"])
            try:
                if self.interrupted is not None:
                    raise self.interrupted
                ws = self.evaluate([z for z, _ in batch])
                for (_, slot), w in zip(batch, ws, strict=True):
                    slot["w"] = w
            except BaseException as err:  # the solver threads must not wait forever
                if not isinstance(err, Exception):  # Ctrl-C: stop, do not go on
                    self.interrupted = err
                for _, slot in batch:
                    slot["error"] = err
            for _, slot in batch:
                slot["done"].set()


def dfols_solves(evaluate: EvaluateCoded, starts: Sequence[np.ndarray], budgets: Sequence[int],
                 failed: np.ndarray, rhobeg: float = 0.1, rhoend: float = 1e-3,
                 log: Log = lambda s: None) -> list[dict]:
    """DFO-LS from each of ``starts`` (coded) with at most ``budgets[i]`` evaluations, the
    solves run at once (:class:`Batcher`). A failed simulation answers ``failed`` (a
    residual vector worse than any seen), which the trust region then avoids. Returns per
    start: ``x``, ``w``, ``jacobian`` (coded), ``nf``, DFO-LS's exit message and
    ``budget_spent`` (it stopped on ``budgets[i]``, not on its own criteria)."""
    import dfols

    batcher = Batcher(evaluate, len(starts))
    out: list[dict] = [{} for _ in starts]

    def solve(i: int) -> None:
        def objfun(z):
            w = batcher(z, i)
            return failed if w is None else w

        try:
            if budgets[i] < len(starts[i]) + 2:
                out[i] = {"error": "budget below the interpolation set"}
                return
            z0 = np.clip(np.asarray(starts[i], float), -1.0, 1.0)
            res = dfols.solve(objfun, z0, bounds=(-np.ones(len(z0)), np.ones(len(z0))),
                              rhobeg=rhobeg, rhoend=rhoend, maxfun=int(budgets[i]),
                              do_logging=False,
                              user_params={"logging.save_diagnostic_info": False})
            out[i] = {"x": np.asarray(res.x, float), "w": np.asarray(res.resid, float),
                      "jacobian": None if res.jacobian is None else
                      np.asarray(res.jacobian, float), "nf": int(res.nf), "message": res.msg,
                      "budget_spent": res.flag == res.EXIT_MAXFUN_WARNING}
        except BaseException as err:  # reported, never a hang of the serving thread
            out[i] = {"error": f"{type(err).__name__}: {err}"}
        finally:
            batcher.leave()

    threads = [threading.Thread(target=solve, args=(i,), daemon=True)
               for i in range(len(starts))]
    for t in threads:
        t.start()
    batcher.serve()
    for t in threads:
        t.join()
    if batcher.interrupted is not None:  # it was logged as a start's error and went on
        raise batcher.interrupted
    for i, o in enumerate(out):
        if "error" in o:
            log(f"    DFO-LS start {i + 1}: {o['error']}")
        else:
            log(f"    DFO-LS start {i + 1}: chi2 {float(o['w'] @ o['w']):.4g} after "
                f"{o['nf']} evaluations ({o['message']})")
    return out


def _jacobian_points(z: np.ndarray, h: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    steps = np.where(z + h <= 1.0, h, -h)
    return [z + steps[i] * np.eye(len(z))[i] for i in range(len(z))], steps


def levenberg_marquardt(evaluate: EvaluateCoded, z0: np.ndarray, w0: np.ndarray,
                        budget: int, max_iter: int = 12, step: float = 0.05,
                        tol: float = 3e-3, log: Log = lambda s: None) -> dict:
    """Bounded derivative-free Levenberg-Marquardt from ``z0`` (its residuals ``w0``): a
    forward-difference Jacobian (``d`` parallel runs) at each new best point, then pairs of
    damped Gauss-Newton steps (two damping values, run together) until one lowers chi2,
    the damping raised a hundredfold after each failed pair (Levenberg 1944, Marquardt
    1963); four failed pairs halve the difference step; below 1.5 % of the range, or after
    two iterations gaining less than ``tol`` (relative) or 0.5 in chi2, it stops. Returns
    ``x``, ``w``, ``jacobian``, ``nf`` (points run), ``message`` in DFO-LS's wording
    ("Warning (max evals)" where the budget or ``max_iter`` ended it, "Success" where it
    converged) and ``budget_spent`` (the former)."""
    d = len(z0)
    best_z, best_w = np.array(z0, float), np.asarray(w0, float)
    used = 0
    jac = None

    def run(zs):
        nonlocal used
        used += len(zs)
        return evaluate(zs)

    def affordable(n):
        return used + n <= budget

    lam, slow = 1e-3, 0
    steps = np.full(d, float(step))
    # DFO-LS's wording, so that callers read either solver's exit the same way
    exhausted = f"Warning (max evals): budget of {budget} points"
    spent = False  # stopped on the budget or max_iter, not on its own criteria
    for it in range(max_iter):
        if not affordable(d + 2):
            message, spent = exhausted, True
            break
        z, w = best_z, best_w
        pts, h = _jacobian_points(z, steps)
        cols = run(pts)
        # an axis whose difference changes the residuals by more than their size has
        # stepped across a narrow valley: difference it again at a quarter of the step
        for _ in range(2):
            wide = [i for i, c in enumerate(cols) if c is not None and steps[i] > 2e-3
                    and np.linalg.norm(c - w) > np.linalg.norm(w)]
            if not wide or not affordable(len(wide) + 2):
                break
            steps[wide] /= 4
            again = run([z + np.where(z[i] + steps[i] <= 1, steps[i], -steps[i]) *
                         np.eye(d)[i] for i in wide])
            h = h.copy()
            for i, c in zip(wide, again, strict=True):
                cols[i] = c
                h[i] = steps[i] if z[i] + steps[i] <= 1 else -steps[i]
        J = np.column_stack([(c - w) / hi if c is not None else np.zeros_like(w)
                             for c, hi in zip(cols, h, strict=True)])
        jac = J
        A, g = J.T @ J, J.T @ w
        scale = np.maximum(np.diag(A), 1e-12 * max(np.max(np.diag(A)), 1e-300))
        old = float(w @ w)
        cands = [(p, c) for p, c in zip(pts, cols, strict=True) if c is not None]
        cand = min(cands, key=lambda pc: float(pc[1] @ pc[1]), default=(z, w))
        for _ in range(4):
            if not affordable(2):
                break
            trials = []
            for mu in (lam, lam * 10):
                s = -np.linalg.solve(A + mu * np.diag(scale) + 1e-12 * np.eye(d), g)
                norm = np.max(np.abs(s))
                if norm > 1.0:  # at most half the coded range per step
                    s = s / norm
                trials.append(np.clip(z + s, -1, 1))
            tried = [(p, c) for p, c in zip(trials, run(trials), strict=True) if c is not None]
            if tried:
                bt = min(tried, key=lambda pc: float(pc[1] @ pc[1]))
                if float(bt[1] @ bt[1]) < old:
                    lam = lam / 3 if bt[0] is trials[0] else lam * 3
                    cand = min(bt, cand, key=lambda pc: float(pc[1] @ pc[1]))
                    break
            lam *= 100
        new = float(cand[1] @ cand[1])
        if new < old:
            best_z, best_w = cand
            slow = slow + 1 if (old - new) / max(old, 1e-300) < tol or old - new < 0.5 else 0
            log(f"    LM iteration {it + 1}: chi2 {old:.4g} -> {new:.4g}")
            if slow >= 2:
                message = "Success: LM gained too little in two iterations"
                break
        elif np.max(steps) > 0.015:
            steps = np.maximum(steps / 2, np.minimum(steps, 2e-3))
            lam = 1e-3
        else:
            spent = not affordable(2)
            message = exhausted if spent else \
                "Success: LM found no lower point at the smallest difference step"
            break
    else:
        message, spent = f"Warning (max evals): {max_iter} iterations", True
    return {"x": best_z, "w": best_w, "jacobian": jac, "nf": used, "message": message,
            "budget_spent": spent}
