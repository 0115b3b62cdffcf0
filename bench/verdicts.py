"""Hand-picked diagnosis cases with known answers on the quick study (issues 16 and 25): the
base parameters off nominal (slide stiffness x1.5, friction transition velocities 1.0 ->
0.65 mm/s), with or without a hidden effect at a chosen place, rig noise, a few candidates
each (the truth, the same effect at another place, other effects). Each case is a verdict
that once failed or that a change of the diagnosis once broke; every one must end as
``expect`` says.

The test suite runs the cases marked ``suite`` (``tests/measure/test_diagnose.py``: one,
the cheapest; the others cost 100-170 s each on 2 cores, 1150 s in all, which the suite's
20 minutes cannot hold beside its other diagnoses); this script runs them all and prints,
per case, the verdict against the expected one, chi2 of H0 and of the best hypothesis,
whether every calibrated candidate nests H0 (ends at or below its chi2), the simulations
and the wall time. The rates over random cases are ``bench/recovery.py``'s.

    python bench/verdicts.py [--workers 2] [--only ID,...] [--store DIR]

Exit status 1 when a case ends otherwise than expected.
"""

from __future__ import annotations

import sys
from pathlib import Path

# bench/signal.py would shadow the standard library's signal module: drop this folder
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]

import argparse  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import tomllib  # noqa: E402
from dataclasses import dataclass  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: two sensitive base parameters (the screen ranks both above 10 %) off by 1.5 and 1/1.54:
#: the friction transition velocities move together (the study's group), 1.0 -> 0.65 mm/s
OFFSETS = {"slide_stiffness": 7.05e5 * 1.5, "slide_v_friction": 0.65, "slide_v_stiction": 0.065}
#: the same offsets as the study's calibration variables
CALIBRATED = {"slide_stiffness": 7.05e5 * 1.5, "slide_friction_velocity": 0.65}
PARAMETERS_OR_NONE = ("parameters", "none")


@dataclass(frozen=True)
class Case:
    """A synthetic measurement of the short quick study with the base ``OFFSETS`` and
    ``hidden`` (``EFFECT@PLACE:name=value,...``, or None), diagnosed among
    ``candidates``; the verdict must be one of ``expect``."""

    id: str
    hidden: str | None
    candidates: tuple[str, ...]
    noise: float = 0.02
    seed: int = 5
    levels: tuple[float, ...] = (0.1,)
    suite: bool = False
    why: str = ""

    @property
    def expect(self) -> tuple[str, ...]:
        return PARAMETERS_OR_NONE if self.hidden is None else (self.hidden.split(":")[0],)


CASES = [
    # two at a non-default place (driveshaft), each against the same effect elsewhere and
    # other effects
    Case("added_mass@driveshaft", "added_mass@driveshaft:added_mass=0.04",
         ("added_mass@driveshaft", "added_mass@crankshaft", "damping@bearing_l3")),
    Case("flexible_mode@driveshaft",
         "flexible_mode@driveshaft:flex_frequency=1800,flex_damping=0.02,flex_mass=0.03",
         ("flexible_mode@driveshaft", "flexible_mode@crankshaft", "added_mass@driveshaft"),
         why="the suite's CLI test diagnoses the same mode at two levels"),
    Case("friction@clutch_drive", "friction@clutch_drive:friction_mu=0.15,friction_velocity=0.5",
         ("friction@clutch_drive", "friction@clutch_crank", "damping@clutch_drive"),
         why="the local search alone names the crank side (README, issue 25)"),
    # deterministic since the solver threads' runs keep a fixed order; it ended "none"
    # until the race's candidates were restarted from H0's refreshed optimum (the true one
    # stalled at chi2 398 on its level from H0's first stall at 725): _restart_race
    Case("preload@crankshaft", "preload@crankshaft:preload_force=15",
         ("preload@crankshaft", "preload@driveshaft", "added_mass@crankshaft"),
         why="sensfw.measure.diagnose._restart_race"),
    Case("contact_hardening@bearing_l1",
         "contact_hardening@bearing_l1:hardening_increase=0.8",
         ("contact_hardening@bearing_l1", "contact_hardening@bearing_l3", "damping@bearing_l1"),
         why="bench/recovery.py's case 4 (in the suite) is a contact hardening too"),
    *(Case(f"noise {noise:g} seed {seed}", None, ("added_mass@crankshaft", "damping@bearing_l3"),
           noise=noise, seed=seed, suite=(noise, seed) == (0.05, 3),
           why=("a damping at bearing l3 traded against the slide damping (correlation -1.00) "
                "and won until H0 was also tried where the leader trades")
           if (noise, seed) == (0.10, 1) else "")
      for noise in (0.05, 0.10) for seed in (1, 2, 3)),
]


def short_quick() -> dict:
    """The quick study (with its [calibration]) on a 0.15 s chirp and a 2e-5 s step, for CI
    time; the synthetic measurements use the same settings."""
    data = tomllib.loads((ROOT / "studies" / "quick.toml").read_text())
    data["excitation"]["duration"] = "0.15 s"
    data["solver"]["step"] = "2e-5 s"
    return data


def study():
    from sensfw.study import Study

    return Study.from_dict(short_quick(), "quick-short")


def measure(study, folder: Path, effect: str | None = None, noise: float = 0.02,
            seed: int = 5, levels=(0.1,)):
    """Synthetic records of ``study`` with the base ``OFFSETS`` and ``effect``, one per
    level (rig noise ``noise`` of each channel's RMS, seeds ``seed``, ``seed + 1``, ...)."""
    from sensfw.measure.io import write_csv
    from sensfw.measure.prepared import load_measurements
    from sensfw.measure.synthetic import Rig, synthesize

    files = []
    Path(folder).mkdir(parents=True, exist_ok=True)
    for i, level in enumerate(levels):
        sig, _ = synthesize(study, sets=OFFSETS, effects=[effect] if effect else [],
                            amplitude=level, rig=Rig(noise=noise, seed=seed + i))
        files.append(write_csv(Path(folder) / f"m{i}.csv", sig, level=level))
    return load_measurements(study, [str(f) for f in files])


def nested(result) -> list[tuple[str, float]]:
    """The calibrated candidates that end above H0's chi2 (none should: each starts where
    it vanishes exactly, and only improving steps are taken)."""
    h0 = result.rows[0]["chi2"]
    return [(r["hypothesis"], r["chi2"]) for r in result.ranking if r["chi2"] > h0 + 1e-9]


def problems(case: Case, result) -> list[str]:
    """What is wrong with ``result`` for ``case`` (empty: it ends as expected): the verdict
    not among ``case.expect``, a calibrated candidate above H0 (:func:`nested`), or, with a
    hidden effect, the best fit's error not below the base parameters' alone."""
    out = []
    if result.verdict not in case.expect:
        out.append(f"verdict {result.verdict}: {result.reason}")
    above = nested(result)
    if above:
        out.append(f"above H0: {above}")
    if case.hidden is not None and not (result.errors["best"] is not None and
                                        result.errors["best"] < result.errors["parameters"]):
        out.append(f"best error {result.errors['best']} not below the parameters' "
                   f"{result.errors['parameters']:.3g} dB")
    return out


def run(case: Case, study, runner, folder: Path):
    """The case's diagnosis (``diagnose`` with ``final=1``) on fresh records in ``folder``."""
    from sensfw.measure.diagnose import diagnose

    meas = measure(study, folder, case.hidden, case.noise, case.seed, case.levels)
    return diagnose(study, meas, runner, candidates=list(case.candidates), final=1)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--only", help="case ids, comma-separated")
    ap.add_argument("--store", type=Path, help="a run store to share (default: a new one)")
    args = ap.parse_args()
    from sensfw.runs import Runner, RunStore

    wanted = [w.strip() for w in args.only.split(",")] if args.only else []
    unknown = [w for w in wanted if w not in {c.id for c in CASES}]
    if unknown:
        ap.error(f"--only: unknown case id(s) {unknown}; known: "
                 + ", ".join(repr(c.id) for c in CASES))
    chosen = [c for c in CASES if not wanted or c.id in wanted]
    tmp = Path(tempfile.mkdtemp(prefix="sensfw-verdicts-"))
    s, wrong = study(), 0
    print(f"{'case':32s} {'suite':5s} {'expected':28s} {'verdict':28s} {'ok':3s} "
          f"{'chi2 H0':>9s} {'chi2 best':>9s} {'nests':5s} {'sims':>5s} {'wall s':>7s}")
    with Runner(RunStore(args.store or tmp / "runs"), backend="processes",
                workers=args.workers) as runner:
        for i, case in enumerate(chosen):
            t0 = time.perf_counter()
            res = run(case, s, runner, tmp / f"case{i}")
            wall = time.perf_counter() - t0
            above = nested(res)
            wrong_here = problems(case, res)
            ok = not wrong_here
            wrong += not ok
            best = min(r["chi2"] for r in res.rows)
            print(f"{case.id:32s} {'yes' if case.suite else '':5s} {'/'.join(case.expect):28s} "
                  f"{res.verdict:28s} {'yes' if ok else 'NO':3s} {res.rows[0]['chi2']:9.1f} "
                  f"{best:9.1f} {'NO' if above else 'yes':5s} "
                  f"{res.n_simulations:5d} {wall:7.0f}", flush=True)
            if not ok:
                print(f"    {'; '.join(wrong_here)}; {case.why}", flush=True)
    print(f"{len(chosen) - wrong} of {len(chosen)} cases end as expected")
    sys.exit(1 if wrong else 0)


if __name__ == "__main__":
    main()
