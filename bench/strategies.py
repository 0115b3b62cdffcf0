"""Design strategies against the conclusions of the paper's pipeline on the shipped model
(issue 28): how many simulations does each need to conclude what the OAT screen + 3^4 full
factorial (120 runs) concludes?

    python bench/strategies.py [--out out/strategies] [--reuse out/paper] [--workers 2]
                               [--budget 45] [--extra 21,27] [--seeds 10]

Every run goes through one run store (``OUT/runs``, also reading ``REUSE/runs``, e.g. the
output folder of ``sensfw run studies/paper.toml``), so a run that several strategies share is
simulated once: the benchmark costs the union of the designs, and each strategy's count is
the number of distinct runs it needs (its union), the nominal reference run included where
its scores need it.

The reference: ``studies/paper.toml`` run as the paper's pipeline, i.e. the OAT screen of the
19 design variables (39 runs with the nominal) scored by the FRF scalar, the top 4 above 10 %
normalised sensitivity, then the 3-level full factorial (81 runs) on them scored by P1, P2
and THD, each fitted by Eq. 18 (product interactions, 15 terms).

A strategy reaches the same conclusions when it keeps the same top 4 in its screen, and its
second stage predicts the full factorial's other runs within the full factorial's own
leave-one-out RMSE and flags the same significant Eq. 18 terms, where "the same significant
terms" means: every term the full factorial flags with p < 0.001 is flagged at p < 0.05, and
none that it finds with p > 0.5 (coded variables). Between the two the full factorial's own
decision is not reproducible: a term at p = 0.001 keeps p < 0.05 in an independent replicate
with probability 0.91, one at p = 0.5 turns significant with probability 0.10 (the argument,
and the choice of the prediction surrogate, are in sensfw/analysis/agreement.py, which the
study reports use too). The strict form, the same set at p < 0.05, is printed too.

Screens: the paper's OAT; Morris (r = 2 trajectories on the 19 variables, the paper's pairs
moved together); Morris with groups (r = 2 on Table 1's seven components, then OAT on the
members of the components whose mu* exceeds 10 % of the largest); the OAT of the seven
components (each moved as a whole), then the OAT of a component's members in the order of
the components' effects while a component's effect reaches the fourth largest member effect
found (sequential group screening); the OAT at one end per variable (every variable at its
min, at its max, or its end drawn at random: ``k + 1`` runs, read from the OAT's own; which
end shows a variable is known only once both have run, so these do not enter the
pipelines); a definitive screening
design on the 19 variables; the two-level main-effect screens with fewer runs than the OAT,
a Plackett-Burman design (20 runs) and a regular resolution-III fraction (2^(19-14), 32
runs). Second stages, on the reference's top-4 box (all of their runs
lie on the full factorial's 3-level grid): Box-Behnken, face-centred central composite, the
three complementary 3^(4-1) generalized subset fractions, and uncertainty sampling (a
Gaussian-process sequence started from the 9-run definitive screening design of the 4
variables, adding the grid point where the surrogates are least certain, one at a time, up
to ``--budget`` runs; it reaches the conclusions at the first count from which every
criterion holds at every later count).

Second stages that count the screen's runs: the OAT screen has already run the nominal and
each of the four selected variables at its min and its max (the others nominal), 9 runs of
the second stage's space. They are runs of a 3-level grid whose middle level is the nominal
(``full_factorial`` with ``centre = "nominal"``), not of the paper's 3^4 grid, whose middle
level is the mid-point (for the three factor-10 variables the nominal is at coded -0.82).
Tried: a face-centred CCD around the nominal (the 9 runs are its axial and centre runs, 16
new corners), D- and I-optimal designs (``optimal``) of ``--extra`` grid runs chosen around
the 9 runs (``augment = "oat"``) or without them and fitted with them, and uncertainty
sampling started from the 9 runs. An optimal design depends on its seed (equally optimal
designs abound on a grid), so each is tried with ``--seeds`` seeds and the benchmark prints
how many of them reach the conclusions. Last, for the terms the full factorial flags with
p < 0.001, the benchmark prints the t statistic to expect from n runs of the same
information per run (|t| sqrt(n / 81)) against the t needed for p < 0.05 with n - 15
degrees of freedom: the runs below which a term is flagged only by luck.
"""

from __future__ import annotations

import sys
from pathlib import Path

# bench/signal.py would shadow the standard library's signal module (imported by the process
# pool's dependencies) when this script's folder is first on the path
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).parent]

import argparse  # noqa: E402
import re  # noqa: E402
import time  # noqa: E402
from collections import defaultdict  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SCREEN_THRESHOLD, TOP = 0.10, 4


# ---- the reference ---------------------------------------------------------------------------
def conclusions(space, ev):
    """The full factorial's conclusions (:class:`sensfw.analysis.agreement.Conclusions`)."""
    from sensfw.analysis.agreement import Conclusions

    return Conclusions(names=space.names, bounds=[(v.low, v.high) for v in space.variables],
                       table=ev.table, scores=ev.scores)


class Bench:
    """The study, the runner, the scorers and the reference conclusions."""

    def __init__(self, runner):
        from sensfw.evaluate import make_scorers, reference_spec
        from sensfw.study import Study

        self.study = Study.load(ROOT / "studies" / "paper.toml")
        self.runner = runner
        screen, doe = self.study.stages
        self.screen_stage, self.doe_stage = screen, doe
        self.frf = make_scorers(self.study, screen)
        self.orders = make_scorers(self.study, doe)
        self.ref_spec = reference_spec(self.study)
        self.ref_key = self.ref_spec.key()
        self.all_space = self.study.space(screen, None)

    def screen(self, space, design, label):
        """(keys incl. the reference run, ScreeningResult) of ``design`` on ``space``."""
        from sensfw.evaluate import evaluate

        ev = evaluate(self.study, space, design, self.runner, self.frf, self.ref_spec,
                      label=label)
        res = ev.design.analyze(space, ev.table, ev.scores[self.screen_stage.scorers[0].key])
        return [*ev.keys, self.ref_key], res

    def second(self, space, design, label):
        from sensfw.evaluate import evaluate

        return evaluate(self.study, space, design, self.runner, self.orders, label=label)


def select(result) -> list[str]:
    return result.select(threshold=SCREEN_THRESHOLD, max_variables=TOP)


# ---- strategies ------------------------------------------------------------------------------
def screens(bench: Bench) -> dict[str, dict]:
    """Every screen: runs (distinct keys), selection, agreement with the reference's top 4."""
    from sensfw.designs import make_design

    space = bench.all_space
    out = {}
    oat = make_design("oat")
    keys, res = bench.screen(space, oat, "screen: OAT")
    out["OAT (paper)"] = {"keys": set(keys), "selected": select(res), "result": res,
                          "runs": dict(zip(oat.generate(space).index, keys, strict=False))}
    keys, res = bench.screen(space, make_design("morris", trajectories=2), "screen: Morris")
    out["Morris r=2"] = {"keys": set(keys), "selected": select(res), "result": res}
    components = defaultdict(list)
    for v in space.variables:
        group = bench.study.parameters[v.members[0]].group
        components[re.sub(r"\W+", "_", group.lower()).strip("_")].append(v.name)
    gm = make_design("morris", trajectories=2, groups=dict(components))
    keys_g, res_g = bench.screen(space, gm, "screen: Morris with groups")
    kept = [g for g in res_g.ranking if res_g.importance[g] > SCREEN_THRESHOLD]
    members = [v for g in kept for v in components[g]]
    sub = bench.study.space(bench.screen_stage, members)
    keys_o, res_o = bench.screen(sub, make_design("oat"), "screen: OAT within groups")
    out["Morris with groups r=2, then OAT"] = {
        "keys": set(keys_g) | set(keys_o), "selected": select(res_o), "result": res_o,
        "detail": f"kept {', '.join(kept)} ({len(members)} variables)"}
    out.update(group_oat(bench, components, out["OAT (paper)"]))
    out.update(one_sided(out["OAT (paper)"]))
    dsd = make_design("definitive_screening")
    keys, res = bench.screen(space, dsd, "screen: definitive screening")
    out["definitive screening"] = {"keys": set(keys), "selected": select(res), "result": res}
    for name, design in (("Plackett-Burman", make_design("plackett_burman")),
                         ("2-level fraction, resolution III",
                          make_design("fractional_factorial", resolution=3))):
        keys, res = bench.screen(space, design, f"screen: {name}")
        out[name] = {"keys": set(keys), "selected": select(res), "result": res,
                     "detail": "; ".join(res.notes)}
    return out


def group_oat(bench: Bench, components: dict[str, list[str]], oat: dict) -> dict[str, dict]:
    """Sequential group screening: the OAT of Table 1's seven components (each moved to its
    min and its max as a whole, ``oat`` with ``groups``), then, in the order of the
    components' effects, the OAT of a component's members while the component's effect
    reaches the ``TOP``-th largest member effect found so far (a component whose effect
    is smaller holds no member above it, if its members do not cancel). The members'
    runs are the paper's OAT's (the same runs, read from the store)."""
    from sensfw.designs import make_design

    space = bench.all_space
    keys_g, res_g = bench.screen(space, make_design("oat", groups=components),
                                 "screen: OAT with groups")
    s_oat = oat["result"].table["sensitivity"]
    groups = res_g.table["sensitivity"]
    keys, found, opened = set(keys_g), {}, []
    for g in res_g.ranking:
        bar = sorted(found.values(), reverse=True)[TOP - 1] if len(found) >= TOP else 0.0
        if groups[g] < bar:
            break
        sub = bench.study.space(bench.screen_stage, components[g])
        k, res = bench.screen(sub, make_design("oat"), f"screen: OAT within {g}")
        keys |= set(k)
        opened.append(g)
        found.update(res.table["sensitivity"].astype(float).to_dict())
    best = max(found.values())
    selected = [v for v in sorted(found, key=found.get, reverse=True)
                if found[v] / best > SCREEN_THRESHOLD][:TOP]
    member = {v: g for g, vs in components.items() for v in vs}
    lost = [v for v in oat["selected"] if member[v] not in opened]
    detail = ("components " + ", ".join(f"{g} {groups[g]:.3g}" for g in res_g.ranking)
              + f"; opened {', '.join(opened)}")
    if lost:
        detail += "; " + ", ".join(f"{v} ({s_oat[v]:.3g} alone, its component "
                                   f"{groups[member[v]]:.3g})" for v in lost)
    return {"OAT with groups, then OAT within": {"keys": keys, "selected": selected,
                                                 "result": res_g, "detail": detail}}


def one_sided(oat: dict, draws: int = 20000) -> dict[str, dict]:
    """One end per variable (``k + 1`` runs instead of ``2 k + 1``), from the paper's OAT's
    own runs: every variable at its min, every one at its max, and each variable's end
    drawn at random (the share of ``draws`` draws that select the OAT's top ``TOP``)."""
    tab = oat["result"].table
    lo, hi = tab["s_min"].abs().to_numpy(), tab["s_max"].abs().to_numpy()
    names = list(tab.index)
    runs = oat["runs"]  # run label -> key

    def pick(s: np.ndarray) -> list[str]:
        order = np.argsort(-s, kind="stable")
        return [names[i] for i in order[:TOP] if s[i] / s.max() > SCREEN_THRESHOLD]

    def keys(end: str) -> set[str]:
        return {runs["nominal"], *(runs[f"{v}:{end}"] for v in names)}

    rng = np.random.default_rng(0)
    ends = rng.random((draws, len(names))) < 0.5
    hits = sum(set(pick(np.where(e, lo, hi))) == set(oat["selected"]) for e in ends)
    # which end shows a variable is known only once both ends have run: a fixed end is no
    # strategy, so these screens do not enter the pipelines (``post_hoc``)
    out = {f"OAT, every variable at its {end} only": {"keys": keys(end), "post_hoc": True,
                                                      "selected": pick(s)}
           for end, s in (("min", lo), ("max", hi))}
    out["OAT, each variable's end drawn at random"] = {
        "keys": keys("min"), "selected": [], "same": f"{hits / draws:.0%} of draws",
        "post_hoc": True,
        "detail": f"{hits} of {draws} draws of the ends (seed 0) select the OAT's top {TOP}"}
    return out


def second_stages(bench: Bench, ref, budget: int) -> dict[str, dict]:
    from sensfw.analysis.agreement import agreement
    from sensfw.designs import make_design
    from sensfw.designs.sequential import run_sequence

    space = bench.study.space(bench.doe_stage, ref.names)
    out = {}
    plans = {"Box-Behnken": make_design("box_behnken", center=1),
             "face-centred CCD": make_design("central_composite", face="ccf", center=[1, 0])}
    for f in range(3):
        plans[f"3^(4-1) subset, fraction {f}"] = make_design("subset", reduction=3, fraction=f)
    for name, design in plans.items():
        ev = bench.second(space, design, f"second stage: {name}")
        out[name] = {"keys": set(ev.keys), **agreement(ref, ev.table, ev.scores)}
    # uncertainty sampling on the full factorial's grid, from the 4-variable DSD
    start = make_design("definitive_screening").generate(space)
    grid = ref.table[space.names]
    trail = []

    def step(seq):
        if len(seq.table) >= 16:  # Eq. 18 needs more runs than its 15 coefficients
            trail.append((len(seq.table), set(seq.keys), agreement(ref, seq.table, seq.scores)))

    run_sequence(bench.study, space, bench.runner, bench.orders, start, grid, budget,
                 on_step=step)
    out["GP uncertainty sampling"] = _sequence_result(trail)
    return out


def screen_evidence(bench: Bench, ref, paper_keys: set[str], budget: int, extra: list[int],
                    seeds: int) -> tuple[dict[str, dict], dict[str, int]]:
    """Second stages that count the OAT screen's 9 runs of the four variables (module
    docstring), and how many of those runs the paper's grid and the nominal-centred grid
    share."""
    from sensfw.analysis.agreement import agreement
    from sensfw.designs import make_design
    from sensfw.designs.sequential import run_sequence
    from sensfw.evaluate import make_specs

    study, space = bench.study, bench.study.space(bench.doe_stage, ref.names)
    oat = make_design("oat").generate(space)
    ev_oat = bench.second(space, oat, "second stage: the OAT's runs")
    oat_keys = set(ev_oat.keys)
    nominal_grid = make_design("full_factorial", centre="nominal").generate(space)
    shared = {"oat": len(oat_keys), "paper grid": len(oat_keys & paper_keys),
              "nominal grid": len(oat_keys & {s.key() for s in
                                              make_specs(study, space, nominal_grid)})}

    def judge(table, label):
        ev = bench.second(space, table, label)
        return {"keys": set(ev.keys), **agreement(ref, ev.table, ev.scores)}

    out = {}
    corners = make_design("full_factorial", levels=2).generate(space)
    out["face-centred CCD around the nominal: OAT's 9 + 16 corners"] = judge(
        pd.concat([oat, corners]), "second stage: CCD around the nominal")
    for n in extra:
        for crit in ("D", "I"):
            rules = {f"{crit}-optimal, {n} runs around the OAT's 9":
                     (dict(augment="oat"), False),
                     f"{crit}-optimal, {n} runs, fitted with the OAT's 9": ({}, True),
                     f"{crit}-optimal, {n} runs": ({}, False)}
            for name, (opts, add_oat) in rules.items():
                design = make_design("optimal", runs=n, criterion=crit, **opts)
                tries = []
                for seed in range(seeds):
                    table = design.generate(space, seed=seed)
                    if add_oat:
                        table = pd.concat([oat, table])
                    tries.append(judge(table, f"second stage: {name}, seed {seed}"))
                hits = sum(t["reached"] for t in tries)
                out[name] = {**tries[0], "reach": (hits, seeds),
                             "detail": f"seed 0 shown; reaches with {hits} of {seeds} seeds "
                                       f"(predicts: {sum(t['predicts'] for t in tries)}, "
                                       f"terms: {sum(t['terms'] for t in tries)})"}
    trail = []

    def step(seq):
        if len(seq.table) >= 16:
            trail.append((len(seq.table), set(seq.keys), agreement(ref, seq.table, seq.scores)))

    run_sequence(study, space, bench.runner, bench.orders, oat, ref.table[space.names], budget,
                 on_step=step)
    out["GP uncertainty sampling from the OAT's 9"] = _sequence_result(trail)
    return out, shared


def _sequence_result(trail) -> dict:
    """A sequence reaches the conclusions at the first count from which every criterion
    holds at every later count (``trail``: (runs, keys, agreement) after each step)."""
    reached = next((i for i in range(len(trail))
                    if all(a["reached"] for _, _, a in trail[i:])), None)
    pick = trail[reached] if reached is not None else trail[-1]
    return {"keys": pick[1], **pick[2],
            "detail": (f"holds from {pick[0]} runs to the budget {trail[-1][0]}"
                       if reached is not None else
                       f"not reached by the budget {trail[-1][0]}"),
            "trail": [(n, a) for n, _, a in trail]}


def binding_terms(ref, runs: list[int]) -> pd.DataFrame:
    """Per score and term the full factorial flags with p < 0.001: its |t| (81 runs, 66
    degrees of freedom), the |t| to expect from n runs with the same information per run,
    |t| sqrt(n / 81), against the |t| that p < 0.05 needs with n - 15 degrees of freedom,
    and the fewest runs at which the expected |t| reaches it."""
    from scipy import stats

    from sensfw.analysis.agreement import ALPHA, MUST

    p_terms = len(ref.p[next(iter(ref.p))])
    n_ff, dof = len(ref.table), len(ref.table) - p_terms
    rows = []
    for label in ref.scores.columns:
        for term, p in ref.p[label].items():
            if p >= MUST or term == "(Intercept)":
                continue
            t = stats.t.isf(p / 2, dof)
            need = next((n for n in range(p_terms + 2, n_ff + 1)
                         if t * np.sqrt(n / n_ff) >= stats.t.isf(ALPHA / 2, n - p_terms)),
                        None)
            row = {"score": label, "term": term, "|t| (81 runs)": round(t, 2)}
            for n in runs:
                row[f"{n} runs: expected / needed"] = (
                    f"{t * np.sqrt(n / n_ff):.2f} / {stats.t.isf(ALPHA / 2, n - p_terms):.2f}")
            row["runs for expected = needed"] = need
            rows.append(row)
    return pd.DataFrame(rows).set_index(["score", "term"])


# ---- printing ---------------------------------------------------------------------------------
SHORT = {"eq18": "eq18", "gaussian_process": "gp"}


def _yes(b) -> str:
    return "yes" if b else "no"


def print_screens(out, top4, ref_keys):
    print(f"\nScreens (reference top {TOP}: {', '.join(top4)})")
    rows = []
    for name, s in out.items():
        rows.append({"strategy": name, "runs": len(s["keys"]),
                     "selected": ", ".join(s["selected"]),
                     "same top 4": s.get("same", _yes(set(s["selected"]) == set(top4))),
                     "shared with the paper's screen": len(s["keys"] & ref_keys)})
    print(pd.DataFrame(rows).set_index("strategy").to_string())
    for name, s in out.items():
        if "detail" in s:
            print(f"  {name}: {s['detail']}")


def print_second(out, ref, title="Second stages on the top-4 box", screen_keys=None):
    print(f"\n{title} (criteria 2 and 3; ratio = RMSE on the unrun "
          "full-factorial points / the full factorial's LOO RMSE "
          + ", ".join(f"{k} {v:.3g}" for k, v in ref.rmse_loo.items()) + ")")
    rows = []
    for name, s in out.items():
        r = {"strategy": name, "runs": len(s["keys"])}
        if screen_keys is not None:
            r["new after the OAT"] = len(s["keys"] - screen_keys)
        for label, a in s["scores"].items():
            if "error" in a:
                r[f"{label}"] = a["error"][:30]
                continue
            r[f"{label} ratio"] = f"{a['ratio']:.2f} ({SHORT[a['surrogate']]})"
            r[f"{label} terms"] = ("same" if a["strict"] else "tol." if a["terms"] else
                                   "no: " + ", ".join(["-" + t for t in a["missed"]]
                                                      + ["+" + t for t in a["wrong"]]))
        r["predicts"] = _yes(s["predicts"])
        r["terms"] = _yes(s["terms"])
        r["reached"] = _yes(s["reached"])
        rows.append(r)
    with pd.option_context("display.width", 250, "display.max_colwidth", 60):
        print(pd.DataFrame(rows).set_index("strategy").to_string())
    print("  terms: 'same' = the same set at p < 0.05; 'tol.' = every term with p < 0.001 in "
          "the full factorial flagged and none with p > 0.5; 'no: -t' = t missed, '+t' = t "
          "flagged wrongly")
    for name, s in out.items():
        if "detail" in s:
            print(f"  {name}: {s['detail']}")
        for n, a in s.get("trail", []):
            print(f"    {n:3d} runs: predicts {_yes(a['predicts'])}, terms {_yes(a['terms'])}"
                  "  (" + ", ".join(f"{k} {v['ratio']:.2f}" for k, v in a["scores"].items()
                                   if "ratio" in v) + ")")


def main() -> None:
    from sensfw.analysis.agreement import MUST, MUST_NOT, agreement
    from sensfw.designs import make_design
    from sensfw.runs import Runner, RunStore

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "strategies")
    ap.add_argument("--reuse", type=Path, action="append", default=[],
                    help="output folder whose run store is read too (e.g. out/paper)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--budget", type=int, default=45,
                    help="runs of the uncertainty-sampling sequence at most")
    ap.add_argument("--extra", type=lambda v: [int(x) for x in v.split(",")],
                    default=[21, 27], help="new runs of the optimal designs (comma-separated)")
    ap.add_argument("--seeds", type=int, default=10,
                    help="seeds each optimal design is tried with")
    args = ap.parse_args()
    t0 = time.perf_counter()
    store = RunStore(args.out / "runs", read_also=[r / "runs" for r in args.reuse])
    with Runner(store, workers=args.workers) as runner:
        bench = Bench(runner)
        keys_oat, res_oat = bench.screen(bench.all_space, make_design("oat"), "paper: OAT")
        top4 = select(res_oat)
        space = bench.study.space(bench.doe_stage, top4)
        ev = bench.second(space, make_design("full_factorial", levels=3), "paper: 3^4")
        ref = conclusions(space, ev)
        paper = {"keys": set(ev.keys), **agreement(ref, ev.table, ev.scores)}
        sc = screens(bench)
        st = {"full factorial 3^4 (paper)": paper, **second_stages(bench, ref, args.budget)}
        se, shared = screen_evidence(bench, ref, paper["keys"], args.budget, args.extra,
                                     args.seeds)
    counts = runner.counts
    print(f"paper's pipeline: OAT screen {len(set(keys_oat))} runs -> "
          f"{', '.join(top4)}; 3^4 full factorial {len(paper['keys'])} runs; "
          f"{len(set(keys_oat) | paper['keys'])} in all")
    for label in ref.scores.columns:
        sig, must, must_not = ref.classes(label)
        print(f"  {label}: significant (p < 0.05, coded) {', '.join(sorted(sig))}; "
              f"must be flagged (p < {MUST}) {', '.join(sorted(must))}; "
              f"{len(must_not)} terms with p > {MUST_NOT}")
    print_screens(sc, top4, set(keys_oat))
    print_second(st, ref)
    print(f"\nThe OAT screen's runs of the four variables: {shared['oat']}; runs of the "
          f"paper's 3^4 grid (mid-point centre) among them: {shared['paper grid']}; of the "
          f"3^4 grid with the nominal as its middle level: {shared['nominal grid']}")
    print_second(se, ref, "Second stages counting the OAT screen's runs",
                 screen_keys=set(keys_oat))
    print("\nTerms the full factorial flags with p < 0.001 (the intercept aside): the |t| "
          "to expect from n runs with the full factorial's information per run, against "
          "the |t| of p < 0.05 with n - 15 degrees of freedom")
    with pd.option_context("display.width", 250):
        print(binding_terms(ref, sorted({21, 27, 30, *args.extra})).to_string())
    st = {**st, **se}
    rows = []
    for sname, s in sc.items():
        if set(s["selected"]) != set(top4) or s.get("post_hoc"):
            continue
        for tname, t in st.items():
            runs = len(s["keys"] | t["keys"])
            if t["reached"] or (runs <= 60 and sname == "OAT (paper)"):
                hits, tries = t.get("reach", (int(t["reached"]), 1))
                rows.append({"screen": sname, "second stage": tname, "runs": runs,
                             "predicts": _yes(t["predicts"]), "terms": _yes(t["terms"]),
                             "reached": _yes(t["reached"]),
                             "seeds reaching": f"{hits} of {tries}" if "reach" in t else "-"})
    table = pd.DataFrame(rows).sort_values("runs", kind="stable")
    print("\nPipelines reaching the paper's conclusions, and every pipeline of at most 60 "
          "runs with the OAT screen (union of their runs; optimal designs: seed 0, and how "
          "many of the seeds reach):")
    with pd.option_context("display.width", 250, "display.max_colwidth", 60):
        print(table.to_string(index=False))
    reached = table[table["reached"] == "yes"]
    if len(reached):
        best = reached.iloc[0]
        print(f"fewest: {best['runs']} runs ({best['screen']} + {best['second stage']}"
              + (f", reaching with {best['seeds reaching']} seeds"
                 if best["seeds reaching"] != "-" else "")
              + f"); the paper's pipeline: {len(set(keys_oat) | paper['keys'])}; bar 60: "
              f"{'met' if best['runs'] <= 60 else 'NOT met'}")
    every = set().union(*(s["keys"] for s in sc.values()), *(t["keys"] for t in st.values()))
    summed = sum(len(s["keys"]) for s in sc.values()) + sum(len(t["keys"])
                                                            for t in st.values())
    print(f"\nbenchmark: {len(every)} distinct runs (the designs' sum: {summed}); this call "
          f"simulated {counts.new}, read {counts.cached} from the store "
          f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    sys.exit(main())
