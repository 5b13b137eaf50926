"""Optimisation runs: start or resume one (gripopt's NSGA-II, in Rust), and read a run
folder back — its tables as DataFrames, a design's recorded grasp, a replay."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping, Optional, Union

import pandas as pd

from . import _gripopt
from ._frames import DESIGN_COLUMNS, HISTORY_COLUMNS, SAMPLE_COLUMNS, frame
from .errors import InputError
from .problem import Problem

PathLike = Union[str, os.PathLike]


@dataclass(frozen=True)
class GenerationReport:
    """One generation of a run, as the ``progress`` callback receives it.

    Attributes:
        generation: completed generations (1 = the initial population).
        max_generations: the run's total.
        evaluations: designs evaluated so far.
        population: population size.
        feasible: feasible members of the population.
        hypervolume: normalised hypervolume of the population's feasible front.
    """

    generation: int
    max_generations: int
    evaluations: int
    population: int
    feasible: int
    hypervolume: float


#: A progress callback: called after every generation (before its checkpoint is written).
#: An exception it raises stops the run after that checkpoint and is raised again by
#: :func:`optimise` / :func:`resume` (the run stays resumable).
ProgressCallback = Callable[[GenerationReport], Any]


@dataclass(frozen=True)
class RecordedDesign:
    """A design read back from a run's recording (the MCAP shards, through gripopt's reader).

    Attributes:
        id: the design id.
        record: its ``/designs`` message (docs/recording.md) as a dict.
        trajectory: its recorded grasp samples (units in ``attrs["units"]``; a compact
            recording keeps a subset of the samples, values to f32 precision).
        resolution: ``"compact"`` or ``"full"``.
        file: the shard it was read from.
    """

    id: int
    record: dict[str, Any]
    trajectory: pd.DataFrame
    resolution: str
    file: Path


def design_id(id: Any) -> int:
    """A design id as given (an int, or a whole float such as a DataFrame cell holds);
    anything else, a fraction or a negative number, is an :class:`InputError` naming it."""
    try:
        whole = int(id)
        exact = whole == id
    except (TypeError, ValueError, OverflowError):
        exact = False
    if not exact or isinstance(id, bool) or whole < 0:
        raise InputError(f"design id {id!r}: a whole number ≥ 0 (the id column of the run's tables)")
    return whole


@dataclass(frozen=True)
class Replay:
    """A design re-simulated and compared with its recording (``gripopt replay``).

    Attributes:
        verified: the re-simulation equals the recording (bitwise for the same build; else
            within 1e-12 relative at full resolution, one f32 unit when compact).
        max_difference: the largest relative difference found.
        compared: trajectory samples compared.
        values_compared: values of the ``/designs`` record compared.
        recomputed_feasible: the re-evaluation's verdict.
        record: the re-evaluation's record (as ``gripopt evaluate --json``).
        file: the shard the design was read from.
        agrees_across_revisions: for a recording by another simulator revision (which this
            one does not reproduce bit for bit), whether the verdict, objectives, violation
            and trajectory end agree within 1e-3 relative; None for the same revision.
    """

    verified: bool
    max_difference: float
    compared: int
    values_compared: int
    recomputed_feasible: bool
    record: dict[str, Any]
    file: Path
    agrees_across_revisions: bool | None = None


class Run:
    """A run folder written by ``gripopt optimise`` / :func:`optimise` (finished, stopped,
    or running: its tables are rewritten whole every generation and read afresh at each
    access).

    A ``Run`` reads the run its folder held when it was opened (run.json's ``run_id``):
    once the folder holds another run (replaced by a copy of another run folder, say) or
    none, every read raises :class:`RunFolderError`; open the folder again to read it.

    Tables carry their units in ``df.attrs["units"]`` and meanings in
    ``df.attrs["meanings"]`` (docs/outputs.md).
    """

    def __init__(self, path: PathLike) -> None:
        self._folder = _gripopt.RunFolder(os.fspath(path))
        self._summary: Optional[dict[str, Any]] = None

    @property
    def summary(self) -> Optional[dict[str, Any]]:
        """What the run did: out (the run folder, a :class:`pathlib.Path`), generations
        (completed), evaluations, front_size, feasible, hypervolume, archive_size,
        archive_hypervolume, interrupted, wall_s. ``front_size`` and ``hypervolume`` are
        pareto.csv's (the reported front; history.csv's ``pareto_hypervolume``, or for a run
        folder of a gripopt before issue 42, whose pareto.csv was the population's front,
        its ``hypervolume``; a robust run that certifies: ``hypervolume`` is the search's
        front's, search_pareto.csv).

        For the run an :func:`optimise` / :func:`resume` call returned, that call's report
        (``wall_s``: that call's wall time). For a run opened from its folder, the same
        keys read from the folder at its last checkpoint (run.json, history.csv,
        pareto.csv, archive.csv; ``wall_s``: over all its processes); None while it has no
        completed generation.
        """
        if self._summary is not None:
            return self._summary
        info = self.info
        done = int(info["completed_generations"])
        if done == 0:
            return None
        history = self.history
        last = history[history["generation"] == done]
        hv = lambda column: float(last[column].iloc[-1]) if len(last) else float("nan")  # noqa: E731
        # pareto.csv's hypervolume; a gripopt before issue 42 reported the population's front
        reported = "pareto_hypervolume" in history and len(last) and pd.notna(last["pareto_hypervolume"].iloc[-1])
        front_hv = "pareto_hypervolume" if reported else "hypervolume"
        return {
            "out": self.path,
            "generations": done,
            "evaluations": int(info["evaluations"]),
            "front_size": len(self.front),
            "feasible": int(last["feasible"].iloc[-1]) if len(last) else None,
            "hypervolume": hv(front_hv),
            "archive_size": len(self.archive),
            "archive_hypervolume": hv("archive_hypervolume"),
            "interrupted": info["status"] == "interrupted",
            "wall_s": float(info["wall_s"]),
        }

    def __repr__(self) -> str:
        return f"<gripopt.Run {str(self.path)!r}>"

    @property
    def path(self) -> Path:
        """The run folder."""
        return Path(self._folder.path)

    @property
    def info(self) -> dict[str, Any]:
        """run.json: settings, status, generations, evaluations, resumes."""
        return self._folder.info()

    @property
    def status(self) -> str:
        """What the run is doing, as ``gripopt show`` says it: ``"running"`` (a process
        runs it), ``"stopped"`` (killed or crashed while running: no process holds the
        folder; resumable from its last checkpoint), ``"interrupted"`` (ctrl-c or an
        error, resumable) or ``"finished"``."""
        return str(self._folder.state())

    @property
    def problem(self) -> Problem:
        """The run's problem in force (its copy in the folder, problem.toml), checked
        against the hash run.json recorded: a copy edited since the run used it raises
        :class:`RunFolderError` naming it (as ``gripopt replay`` and ``verify`` refuse it)."""
        return Problem(self._folder.problem())

    @property
    def front(self) -> pd.DataFrame:
        """pareto.csv: the run's front, by id: the best non-dominated designs it found (its
        archive's, at most the population size, chosen by hypervolume; docs/outputs.md)."""
        return frame(self._folder.table("front"), DESIGN_COLUMNS)

    @property
    def population(self) -> pd.DataFrame:
        """population.csv: the whole population, by rank then id, with discard stages and reasons."""
        return frame(self._folder.table("population"), DESIGN_COLUMNS)

    @property
    def archive(self) -> pd.DataFrame:
        """archive.csv: every feasible non-dominated design evaluated in the run, by id."""
        return frame(self._folder.table("archive"), DESIGN_COLUMNS)

    @property
    def history(self) -> pd.DataFrame:
        """history.csv: per generation, evaluations, feasible count and hypervolumes."""
        return frame(self._folder.table("history"), HISTORY_COLUMNS)

    def design(self, id: int) -> RecordedDesign:
        """Design ``id`` as recorded: its ``/designs`` record and grasp trajectory, read
        from the MCAP shard that holds it (one chunk read)."""
        id = design_id(id)
        record, samples, resolution, file = self._folder.design(id)
        return RecordedDesign(id, record, frame(samples, SAMPLE_COLUMNS), resolution, Path(file))

    def replay(self, id: int) -> Replay:
        """Re-simulate design ``id`` from its recorded parameters and compare it with its
        recording."""
        r = self._folder.replay(design_id(id))
        return Replay(
            verified=r["verified"],
            max_difference=r["max_difference"],
            compared=r["compared"],
            values_compared=r["values_compared"],
            recomputed_feasible=r["recomputed_feasible"],
            record=r["fresh"],
            file=Path(r["file"]),
            agrees_across_revisions=r["agrees_across_revisions"],
        )

    def resume(
        self,
        generations: Optional[int] = None,
        threads: Optional[int] = None,
        force: bool = False,
        progress: Optional[ProgressCallback] = None,
    ) -> "Run":
        """Continue this run: :func:`resume` on its folder (:class:`RunFolderError` where the
        folder no longer holds this run)."""
        self._folder.info()
        return resume(self.path, generations=generations, threads=threads, force=force, progress=progress)


def _callback(progress: Optional[ProgressCallback]) -> Optional[Callable[[dict[str, Any]], Any]]:
    """The callback for the native run; anything but None or a callable is an
    :class:`InputError` naming ``progress``, before anything is written."""
    if progress is None:
        return None
    if not callable(progress):
        raise InputError(
            f"progress = {progress!r}: must be a callable taking a GenerationReport, or None",
            field="progress",
        )
    return lambda report: progress(GenerationReport(**report))


def _record(record: Union[bool, Mapping[str, Any]]) -> Union[bool, dict[str, Any]]:
    """``record`` for the native run: True (the defaults), False (nothing), or a dict of
    options (the library checks each); anything else is an :class:`InputError` naming
    ``record``."""
    if record is True or record is False:
        return record
    if not isinstance(record, Mapping):
        raise InputError(
            f"record = {record!r}: must be True, False or a mapping of recording options "
            '(e.g. {"trajectories": "feasible"})',
            field="record",
        )
    try:
        # plain values only (what run.json's `recording` holds)
        return json.loads(json.dumps(dict(record)))
    except (TypeError, ValueError) as e:
        raise InputError(f"record = {record!r}: options must be plain values ({e})", field="record") from None


def _summary(native: Mapping[str, Any]) -> dict[str, Any]:
    """A native run's summary, ``out`` a :class:`pathlib.Path` (as :attr:`Run.summary`
    read from a folder gives it)."""
    summary = dict(native)
    summary["out"] = Path(summary["out"])
    return summary


def optimise(
    problem: Union[Problem, PathLike],
    out: PathLike,
    *,
    pop: int = 100,
    generations: int = 50,
    seed: int = 1,
    threads: Optional[int] = None,
    record: Union[bool, Mapping[str, Any]] = True,
    progress: Optional[ProgressCallback] = None,
) -> Run:
    """Run gripopt's NSGA-II on ``problem`` into the run folder ``out`` (as ``gripopt
    optimise``): every generation checkpointed, the tables, plots and MCAP recording
    written as it goes.

    Args:
        problem: a :class:`Problem` or a problem file. The run runs exactly the problem's
            text. Where that text is the current content of the file the problem was loaded
            from, the run starts from that file and records it as its source (as
            ``gripopt optimise FILE``: a resume follows the file's edits, refused unless
            ``force``). Otherwise (a problem given as text, named after a file that does
            not exist or holds other text, or a file edited since it was loaded: a
            :class:`GripoptWarning` says so) its text is written into ``out`` as
            problem.toml, the run's source, which needs ``out`` new or empty.
        out: the run folder (new or empty).
        pop: population size.
        generations: total generations (1 = the initial population).
        seed: the seed; it fixes the run (whatever the thread count).
        threads: worker threads (None: all cores).
        record: record every design and grasp to MCAP (True), nothing (False), or a
            mapping of recording options over the defaults (the fields of run.json's
            ``recording``, e.g. ``{"trajectories": "feasible", "resolution": "full"}``).
        progress: called with a :class:`GenerationReport` after every generation.

    Returns:
        The :class:`Run` (its ``summary`` says what the run did).

    Raises:
        KeyboardInterrupt: ctrl-c (or a notebook's stop button): the run stopped after the
            current generation's checkpoint and can be continued with :func:`resume`.
        GripoptError: bad input (:class:`InputError`, e.g. a folder that holds a run) or a
            failed run (:class:`RunStoppedError`, resumable).
    """
    callback, options = _callback(progress), _record(record)
    if not isinstance(problem, Problem):
        problem = Problem.load(problem)
    summary = _gripopt.optimise(problem._native, os.fspath(out), pop, generations, seed, threads, options, callback)
    run = Run(out)
    run._summary = _summary(summary)
    return run


def resume(
    path: PathLike,
    *,
    generations: Optional[int] = None,
    threads: Optional[int] = None,
    force: bool = False,
    progress: Optional[ProgressCallback] = None,
) -> Run:
    """Continue the run in ``path`` (stopped, killed or finished) exactly where its last
    checkpoint left it, as ``gripopt resume``.

    Args:
        path: the run folder.
        generations: the new total (None: the run's own).
        threads: worker threads (None: all cores).
        force: resume although the problem file or the checkpoint's checksum changed.
        progress: called with a :class:`GenerationReport` after every generation.
    """
    summary = _gripopt.resume(os.fspath(path), generations, threads, force, _callback(progress))
    run = Run(path)
    run._summary = _summary(summary)
    return run
