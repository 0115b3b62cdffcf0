"""Design strategies compared on the same model: which ranks the parameters right for the
fewest runs?

Each design runs on the study's first (screening) stage — its variables and its scorer —
sharing one run store, and its analysis ranks the variables. The reference ranking is the
total Sobol' index of a surrogate (Gaussian process by default) trained on a large Latin
hypercube; its cross-validated Q^2 says how far to trust it. Agreement is the overlap of the
top-k variables and Kendall's tau between importance vectors.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from scipy.stats import kendalltau

from ..errors import AnalysisError, OptionError
from ..runs import Runner
from ..study import Study

#: a reference surrogate whose k-fold Q² is below this predicts too poorly for its Sobol'
#: ranking to judge designs by (a 20-run reference on the quick study: Q² -0.44, total
#: effects summing to 1.7, a variable the OAT finds inert ranked second)
TRUSTED_Q2 = 0.5


def reference_notes(q2: float | None) -> list[str]:
    """What to say of a reference surrogate of k-fold Q² ``q2``: nothing at
    :data:`TRUSTED_Q2` or above, else that its ranking is no reference."""
    if q2 is not None and q2 >= TRUSTED_Q2:
        return []
    return [f"the reference surrogate predicts its own runs poorly (Q² k-fold "
            f"{'n/a' if q2 is None else f'{q2:.3f}'}, below {TRUSTED_Q2:g}): its Sobol' "
            "ranking is no reference, and the designs' agreement with it means little; give "
            "more --reference-runs"]


def _simulation_seconds(runner: Runner, keys: Sequence[str]) -> float:
    total = 0.0
    for k in set(keys):
        rec = runner.store.record(k)
        total += float(rec.get("wall", 0.0)) if rec else 0.0
    return total


def build_comparison(study: Study, designs: Sequence[str], options: dict[str, dict],
                     reference_runs: int | None, reference_surrogate: str) -> dict:
    """Every plugin a comparison uses, built with its options before anything runs: the
    designs, the reference Latin hypercube and the reference surrogate. Every problem is
    reported at once, at the name it has on the command line (``morris.trajectories``,
    ``reference_surrogate``), in one :class:`~sensfw.errors.OptionError`."""
    from ..pipeline import stage_variables
    from ..plugins import designs as design_registry
    from ..plugins import surrogates
    from ..study.checks import plugin_problems

    stage = study.stages[0]
    space = study.space(stage, stage_variables(study, stage, {}))
    problems = [(f"{name}", f"options for a design that is not compared ({', '.join(designs)})")
                for name in options if name not in designs]
    made = {}
    for name in designs:
        made[name], found = plugin_problems(design_registry, name, options.get(name, {}), name)
        problems += found
    n_ref = reference_runs or 10 * len(space)
    lhs, found = plugin_problems(design_registry, "lhs", {"samples": n_ref}, "reference_runs")
    if found:
        problems.append(("reference_runs", f"reference_runs must be an integer >= 2, got "
                                           f"{n_ref!r}"))
    opts = {"bounds": [(v.low, v.high) for v in space.variables]}
    if reference_surrogate == "gaussian_process":
        opts["log_features"] = "auto"  # factor-10 ranges vary evenly per decade
    sur, found = plugin_problems(surrogates, reference_surrogate, opts, "reference_surrogate")
    problems += found
    if problems:
        lines = "\n".join(f"  {path}: {msg}" for path, msg in problems)
        raise OptionError(f"compare-designs: {len(problems)} problem(s) of its options:\n"
                          f"{lines}", option=problems[0][0], problems=problems)
    return {"stage": stage, "space": space, "designs": made, "lhs": lhs,
            "surrogate": sur, "bounds": opts["bounds"]}


def compare_designs(study: Study, runner: Runner, designs: Sequence[str],
                    options: dict[str, dict] | None = None, reference_runs: int | None = None,
                    reference_surrogate: str = "gaussian_process", top_k: int | None = None,
                    log=lambda s: None) -> dict:
    """Each of ``designs`` (with ``options`` by design name) on the study's first stage,
    against the reference ranking (:func:`build_comparison` checks them all before the
    first simulation)."""
    from ..analysis.sobol import sobol_indices
    from ..analysis.validation import validate
    from ..evaluate import evaluate, make_scorers, needs_reference, reference_spec

    options = options or {}
    built = build_comparison(study, designs, options, reference_runs, reference_surrogate)
    stage, space, bounds = built["stage"], built["space"], built["bounds"]
    scorers = make_scorers(study, stage)
    label = (stage.select.by if stage.select and stage.select.by else stage.scorers[0].key)
    scorers = {label: scorers[label]}
    k = len(space)
    top_k = top_k or (stage.select.max_variables if stage.select and
                      stage.select.max_variables else min(4, k))
    reference = None
    if needs_reference(scorers):
        ref = reference_spec(study)
        runner.run([ref], label="reference run")
        res = runner.load(ref.key())
        if res is None or not res.ok:
            raise AnalysisError("the nominal reference run failed")
        reference = res.signals

    # the reference ranking: Sobol' total indices of a surrogate on a large LHS
    lhs = built["lhs"]
    log(f"reference: lhs with {lhs.n_runs(space)} runs + {reference_surrogate}")
    ev = evaluate(study, space, lhs, runner, scorers, reference, label="reference lhs")
    table, keys, failed = ev.table, ev.keys, ev.failed
    y = ev.scores[label].to_numpy(float)
    ok = np.isfinite(y)
    sur = built["surrogate"].fit(table.loc[ok], y[ok])
    quality = validate(sur, table.loc[ok], y[ok], seed=study.spec.study.seed)
    sob = sobol_indices(sur, bounds, space.names, n=1024, seed=study.spec.study.seed)
    ref_imp = sob["ST"].clip(lower=0)
    ref_rank = list(ref_imp.sort_values(ascending=False).index)
    reference_block = {
        "design": "lhs", "runs": len(table), "failed": len(failed),
        "surrogate": reference_surrogate, "q2_loo": quality["q2_loo"],
        "q2_kfold": quality["q2_kfold"], "ranking": ref_rank,
        "sobol": sob.to_dict(orient="index"),
        "simulation_s": _simulation_seconds(runner, keys),
        "notes": reference_notes(quality["q2_kfold"]),
    }
    for n in reference_block["notes"]:
        log(f"warning: {n}")

    rows = []
    for name in designs:
        log(f"design {name}")
        ev = evaluate(study, space, built["designs"][name], runner, scorers, reference,
                      label=name)
        table, keys, failed, wall = ev.table, ev.keys, ev.failed, ev.wall
        try:
            res = ev.design.analyze(space, table, ev.scores[label].to_numpy(float))
        except AnalysisError as err:  # every run failed: the design ranks nothing
            rows.append({"design": name, "options": options.get(name, {}),
                         "runs": len(table), "failed": len(failed), "wall_s": wall,
                         "simulation_s": _simulation_seconds(runner, keys), "ranking": [],
                         "importance": {}, "top_k_overlap": 0.0, "kendall_tau": None,
                         "notes": [str(err)]})
            continue
        imp = res.importance.reindex(space.names).fillna(0.0)
        rank = list(imp.sort_values(ascending=False, kind="stable").index)
        overlap = len(set(rank[:top_k]) & set(ref_rank[:top_k])) / top_k
        tau = kendalltau(imp.to_numpy(), ref_imp.reindex(space.names).to_numpy()).statistic
        rows.append({"design": name, "options": options.get(name, {}),
                     "runs": len(table), "failed": len(failed), "wall_s": wall,
                     "simulation_s": _simulation_seconds(runner, keys), "ranking": rank,
                     "importance": imp.to_dict(), "top_k_overlap": overlap,
                     "kendall_tau": float(tau) if np.isfinite(tau) else None,
                     "notes": res.notes})
    reaching = [r for r in rows if r["top_k_overlap"] == 1.0]
    best = min(reaching, key=lambda r: r["runs"])["design"] if reaching else None
    return {"study": study.name, "scorer": label, "variables": space.names, "top_k": top_k,
            "reference": reference_block, "designs": rows,
            "fewest_runs_to_reference_top_k": best}


def agreement_table(result: dict) -> pd.DataFrame:
    return pd.DataFrame([{"design": r["design"], "runs": r["runs"],
                          "simulation s": r["simulation_s"],
                          f"top-{result['top_k']} overlap": r["top_k_overlap"],
                          "Kendall tau": r["kendall_tau"],
                          "ranking": ", ".join(r["ranking"][:result["top_k"]])}
                         for r in result["designs"]]).set_index("design")
