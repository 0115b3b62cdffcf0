"""What every command shares: the typer app, the consoles, the option types, the error
handling (user errors exit with status 2 and no traceback), the progress bar and the runner."""

from __future__ import annotations

import contextlib
import functools
import json
from collections.abc import Callable
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape

from ..errors import SensfwError

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="Which parameters of a nonlinear multibody model matter, and does the "
                       "model agree with the rig?")
console = Console(stderr=True)
#: results on stdout: plain text (square brackets in them are intervals, section names and
#: file names, never rich markup)
out = Console(markup=False)


def say(text: str, style: str = "cyan") -> None:
    """A progress line of a long command on stderr. ``text`` is printed as it is: its square
    brackets (``[calibration] parameters``, a file name) are not taken for rich markup."""
    console.print(f"[{style}]{escape(text)}[/]", highlight=False)


StudyFile = Annotated[Path, typer.Argument(help="study TOML file")]
#: the output folder of a command (the default is the command's own)
OutDir = Annotated[Path, typer.Option("--out", "-o")]
Workers = Annotated[int | None, typer.Option(min=1, help="worker processes (default: "
                                                          "cores)")]


def _backend(value: str | None) -> str | None:
    """``--backend`` checked before anything is loaded or run."""
    from ..runs.executor import BACKENDS

    if value is not None and value not in BACKENDS:
        raise typer.BadParameter(f"{value!r}: use one of {', '.join(BACKENDS)}")
    return value


Backend = Annotated[str | None, typer.Option(help="serial | processes | dask",
                                             callback=_backend)]
Scheduler = Annotated[str | None, typer.Option(help="Dask scheduler tcp://host:port")]
ShowProgress = Annotated[bool, typer.Option(help="show the progress bar")]


class Terminated(KeyboardInterrupt):
    """SIGTERM (``timeout``, ``kill``, a batch scheduler), raised where Ctrl-C would be, so
    the workers are stopped and the finished runs kept the same way."""


def _on_sigterm(signum, frame):
    raise Terminated


def _user_errors(fn):
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        import signal
        import threading

        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGTERM, _on_sigterm)
        try:
            return fn(*args, **kwargs)
        except SensfwError as err:
            console.print(f"[bold red]error:[/] {escape(str(err))}", highlight=False,
                          markup=True, soft_wrap=True)
            raise typer.Exit(code=2) from None
        except KeyboardInterrupt as err:
            console.print("[yellow]interrupted; finished runs are kept in the run store[/]")
            raise typer.Exit(code=143 if isinstance(err, Terminated) else 130) from None
    return wrapper


def command(name: str | None = None) -> Callable[[Callable], Callable]:
    """Register a function as a command of :data:`app` (named ``name``, default: after the
    function) whose user errors exit with status 2 (:func:`_user_errors`)."""
    def register(fn: Callable) -> Callable:
        return app.command(name)(_user_errors(fn))
    return register


class RichProgress:
    """Runs done/failed with ETA, one bar per batch of runs."""

    def __init__(self, enabled: bool = True):
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        self.enabled = enabled
        self._progress = Progress(
            TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
            TextColumn("[red]{task.fields[failed]} failed"),
            TextColumn("cached {task.fields[cached]}"),
            TimeElapsedColumn(), TextColumn("ETA"), TimeRemainingColumn(),
            console=console, disable=not enabled, transient=False)
        self._task = None

    def start(self, label: str, total: int, cached: int, failed: int = 0) -> None:
        if not self._progress.live.is_started:
            self._progress.start()
        self._task = self._progress.add_task(label, total=total, completed=cached,
                                             failed=failed, cached=cached)

    def advance(self, ok: bool) -> None:
        task = self._progress.tasks[self._task]
        self._progress.update(self._task, advance=1,
                              failed=task.fields["failed"] + (0 if ok else 1))

    def stop(self) -> None:
        pass

    def close(self) -> None:
        if self._progress.live.is_started:
            self._progress.stop()


def _runner(study, out_dir: Path, workers, backend, scheduler, retry_failed=False,
            progress=True, read_also=()):
    from ..runs import Runner, RunStore

    ex = study.spec.execution
    return Runner(store=RunStore(out_dir / "runs", read_also=read_also),
                  backend=backend or ("dask" if scheduler else ex.backend),
                  workers=workers or ex.workers, scheduler=scheduler or ex.scheduler,
                  progress=RichProgress(progress), retry_failed=retry_failed)


@contextlib.contextmanager
def _running(study, out_dir: Path, workers, backend, scheduler, progress, read_also=()):
    """A Runner on ``out_dir/runs`` (reading also the run stores ``read_also``); its
    progress bar and workers are closed on exit, and the runs that failed are counted
    (a calibration goes on around them, so nothing else would say so)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    runner = _runner(study, out_dir, workers, backend, scheduler, progress=progress,
                     read_also=read_also)
    try:
        yield runner
    finally:
        runner.progress.close()
        runner.close()
    c = runner.counts
    if c.failed:
        say(f"notice: {c.failed} of {c.total} runs failed; their errors are in the run "
            f"store {out_dir / 'runs'}", style="yellow")


def option_value(text: str) -> object:
    """A command-line option's value: JSON where it parses (``6`` an integer, ``0.5`` a
    float, ``true`` a boolean), else the string itself."""
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return text


def _json(path: Path, data) -> None:
    from ..results import jsonable

    path.write_text(json.dumps(jsonable(data), indent=1))


Measured = Annotated[list[Path], typer.Option("--measured", "-m",
                                              help="a measurement: .csv, .uff, an LMS .mat "
                                                   "export or a folder of them, a folder of "
                                                   "level folders; -m again for more")]


