"""The study file of a conservation sweep: a scene and the numbers to vary over it.

A *study file* names a scene and the numbers to vary::

    title = "Energy drift toward the separatrix"
    scene = "../free_body.toml"            # relative to this file; or an inline [scene] table

    [sweep]
    kind = "grid"                          # the Cartesian product of the parameters' values
    [sweep.parameters]
    "initial.rates[0]" = { start = 0.25, stop = 2.0, count = 8 }
    "body.inertia[1]" = [1.5, 1.75]

    [run]
    backend = "local"                      # or "dask"
    workers = 2

Every *member* is the scene with its numbers substituted exactly (a grid's values as decimal
text, so a quad study keeps exact inputs; a random draw as the double drawn), validated like
any scene. Running a study: :mod:`.sweep`; its file: :mod:`.sweep_result`.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from ..core.errors import SceneError
from ..core.precision import (
    Number,
    Precision,
    exact_decimal,
    exact_fraction,
    fraction_text,
    scene_mpf,
    shown,
)
from ..core.scene import Scene, check_keys, checked_numbers, number, read_toml
from ..core.scene_dicts import parse_path, plain_copy, set_at, show_path

KINDS = ("grid", "random")
BACKENDS = ("local", "dask")
DISTRIBUTIONS = ("uniform", "normal")

#: Members per batch on the local backend, and at most per task on Dask: small enough that an
#: interrupted sweep loses little and heyoka's ensemble holds few integrator copies at once,
#: large enough that a task's overhead (building the members' models, a round trip to the
#: scheduler) stays small beside its propagation.
DEFAULT_CHUNK = 256
#: Members a study may have (a grid's product of counts, a random ensemble's count): ten
#: times the largest ensemble we validate with, and refused before any value is drawn
#: (10¹² members once took all memory, or a minute, just to list them).
MAX_MEMBERS = 10**6


#: A member: its index and the values of the swept parameters.
Member = tuple[int, tuple[Number, ...]]


# ---------------------------------------------------------------------- the study file
@dataclass(frozen=True)
class Parameter:
    """One swept number.

    Attributes
    ----------
    name
        The dotted scene path as written, e.g. ``"initial.rates[0]"``.
    path
        Its keys and list indices, e.g. ``("initial", "rates", 0)``.
    values
        A grid's values (decimal text, or the numbers as written in a list).
    distribution
        A random ensemble's ``(kind, (a, b))``: ``("uniform", (lo, hi))`` or
        ``("normal", (mean, sd))``.
    """

    name: str
    path: tuple[str | int, ...]
    values: tuple[Number, ...] | None = None
    distribution: tuple[str, tuple[Number, Number]] | None = None


@dataclass(frozen=True)
class RunOptions:
    """Where and how to integrate: the ``[run]`` table (command-line options override it).

    Attributes
    ----------
    backend
        ``"local"`` (threads on this machine) or ``"dask"``.
    scheduler
        A Dask scheduler's address; None starts a ``distributed.LocalCluster`` (and closes it).
    workers
        Threads (local) or worker processes of the LocalCluster (default: the CPU count).
    chunk
        Members per task on Dask, per batch on the local backend (default: see
        :func:`run_sweep`).
    """

    backend: str = "local"
    scheduler: str | None = None
    workers: int | None = None
    chunk: int | None = None
    #: What a refusal of the scheduler names: the study's field or the command-line option.
    scheduler_field: str = field(default="run.scheduler", compare=False)

    @classmethod
    def parse(
        cls,
        table: Mapping[str, Any],
        where: str = "run",
        scheduler_field: str | None = None,
        options: Iterable[str] = (),
    ) -> RunOptions:
        """The options of ``table`` (the study's ``[run]``), refusals naming ``where.KEY``, or
        the command-line option ``--KEY`` for the keys in ``options`` (overrides)."""
        check_keys(table, ["backend", "scheduler", "workers", "chunk"], where)
        given = set(options)

        def name(key: str) -> str:
            return f"--{key}" if key in given else f"{where}.{key}"

        named = scheduler_field or name("scheduler")
        scheduler = table.get("scheduler")
        if scheduler is not None:
            check_address(scheduler, named)
        backend = table.get("backend", "dask" if scheduler else "local")
        if backend not in BACKENDS:
            raise SceneError(name("backend"), f"must be one of {BACKENDS}, got {backend!r}")
        if scheduler and backend != "dask":
            raise SceneError(named, "is a Dask scheduler: it needs backend = 'dask'")
        workers = _count(table.get("workers"), name("workers"))
        if scheduler and workers is not None:
            raise SceneError(
                name("workers"),
                "applies to this machine (threads, or the LocalCluster's processes); with a "
                "scheduler the cluster's own workers run the sweep",
            )
        chunk = _count(table.get("chunk"), name("chunk"))
        return cls(backend, scheduler, workers, chunk, named)


#: The schemes whose address is ``host:port``.
_HOST_PORT = ("tcp", "tls", "ws", "wss")


def check_address(address: Any, name: str) -> None:
    """Refuse a scheduler address that dask.distributed could not connect to, naming ``name``.

    Checked when the study is read, before anything is integrated or written, with
    distributed's own parser (when distributed is not installed, running the sweep says so).
    """
    example = "an address like 'tcp://host:8786'"
    if not isinstance(address, str) or not address.strip():
        raise SceneError(name, f"must be {example}, got {address!r}")
    try:
        from distributed.comm.addressing import parse_address, parse_host_port
        from distributed.comm.registry import get_backend
    except ImportError:
        return
    try:
        scheme, location = parse_address(address)
        get_backend(scheme)
        if scheme in _HOST_PORT:
            host, port = parse_host_port(location)
            if not host:
                raise ValueError("no host")
            if not 1 <= int(port) <= 65535:
                raise ValueError(f"port {port} is not in 1 … 65535")
    except ValueError as exc:
        raise SceneError(name, f"must be {example}, got {address!r} ({exc})") from None


@dataclass(frozen=True)
class Study:
    """A validated study: the base scene, the swept parameters, how to run.

    Build one with :func:`load_study` or :meth:`from_dict`.
    """

    title: str
    scene: Mapping[str, Any]
    scene_file: str | None
    kind: str
    parameters: tuple[Parameter, ...]
    count: int | None
    seed: int | None
    run: RunOptions
    source: Mapping[str, Any] = field(default_factory=dict)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], base_dir: str | Path | None = None) -> Study:
        """Validate a study given as nested dictionaries (the TOML document's shape).

        ``base_dir``: where a ``scene = "PATH"`` is relative to (default: the current
        directory).
        """
        if not isinstance(data, Mapping):
            raise SceneError("study", f"must be a table, got {type(data).__name__}")
        check_keys(data, ["title", "scene", "sweep", "run"], "")
        title = data.get("title", "")
        if not isinstance(title, str):
            raise SceneError("title", f"must be a string, got {title!r}")
        scene, scene_file = _base_scene(data.get("scene"), base_dir)

        sweep = data.get("sweep")
        if sweep is None:
            raise SceneError(
                "sweep", "is required: kind = 'grid' or 'random', and [sweep.parameters]"
            )
        check_keys(sweep, ["kind", "parameters", "count", "seed"], "sweep")
        kind = sweep.get("kind")
        if kind not in KINDS:
            raise SceneError("sweep.kind", f"must be one of {KINDS}, got {kind!r}")
        count = seed = None
        if kind == "grid":
            for key in ("count", "seed"):
                if key in sweep:
                    raise SceneError(
                        f"sweep.{key}",
                        "applies to kind = 'random' only (a grid has the product of its "
                        "parameters' counts as members)",
                    )
        else:
            for key in ("count", "seed"):
                if key not in sweep:
                    raise SceneError(f"sweep.{key}", "is required for kind = 'random'")
            count = _required_count(sweep["count"], "sweep.count", MAX_MEMBERS)
            seed = sweep["seed"]
            if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
                raise SceneError("sweep.seed", f"must be an integer >= 0, got {seed!r}")

        table = sweep.get("parameters")
        if not isinstance(table, Mapping) or not table:
            raise SceneError(
                "sweep.parameters",
                'must be a table of swept numbers, e.g. "initial.rates[0]" = ...',
            )
        precision = Scene.from_dict(scene).integrator.precision
        # The values as written, in the members' precision: refused by the parameter's name
        # here rather than by the member's field once the sweep runs.
        with checked_numbers(precision):
            parameters = tuple(
                _parameter(name, spec, kind, scene, precision) for name, spec in table.items()
            )
        if kind == "grid" and (size := math.prod(len(p.values) for p in parameters)) > MAX_MEMBERS:
            raise SceneError(
                "sweep.parameters",
                f"a grid of {size} members (the product of the counts), more than {MAX_MEMBERS}",
            )
        run = RunOptions.parse(data.get("run", {}))
        source = {"title": title, "scene": scene, "scene_file": scene_file, "sweep": sweep}
        return cls(title, scene, scene_file, kind, parameters, count, seed, run, plain_copy(source))

    @functools.cached_property
    def precision(self) -> Precision:
        """The base scene's precision (every member's)."""
        return Scene.from_dict(self.scene).integrator.precision

    @property
    def size(self) -> int:
        """Number of members."""
        if self.kind == "random":
            return int(self.count)
        return math.prod(len(p.values) for p in self.parameters)

    def members(self) -> list[tuple[Number, ...]]:
        """Every member's parameter values, in the order of :attr:`parameters`.

        A grid is the Cartesian product, the first parameter varying slowest; a random
        ensemble draws each parameter's ``count`` values in turn from
        ``numpy.random.default_rng(seed)`` (doubles, substituted exactly).
        """
        if self.kind == "grid":
            return list(itertools.product(*(p.values for p in self.parameters)))
        rng = np.random.default_rng(self.seed)
        columns = []
        for p in self.parameters:
            kind, (a, b) = p.distribution
            a, b = float(exact_fraction(a)), float(exact_fraction(b))
            draw = (
                rng.uniform(a, b, self.count) if kind == "uniform" else rng.normal(a, b, self.count)
            )
            columns.append([float(v) for v in draw])
        return list(zip(*columns, strict=True))

    def member_dict(self, values: Sequence[Number]) -> dict[str, Any]:
        """The scene dictionary of the member with these parameter values (the tables and lists
        on the way to a value copied, the rest shared with the study's scene, which nothing
        changes: :meth:`Scene.from_dict` copies what it keeps)."""
        data = dict(self.scene)
        for p, value in zip(self.parameters, values, strict=True):
            set_at(data, p.path, value)
        return data

    def member_scene(self, index: int, values: Sequence[Number]) -> Scene:
        """The validated scene of member ``index``.

        Raises
        ------
        SceneError
            Naming the member, its parameter values and the field that is wrong.
        """
        try:
            return Scene.from_dict(self.member_dict(values))
        except SceneError as exc:
            raise SceneError(
                f"member {index} ({self.describe(values)}): {exc.field}", exc.constraint
            ) from None

    def describe(self, values: Sequence[Number]) -> str:
        """``name = value, ...`` for a member's values."""
        return ", ".join(
            f"{p.name} = {show_number(v)}" for p, v in zip(self.parameters, values, strict=True)
        )

    def to_dict(self) -> dict[str, Any]:
        """The study as a plain dictionary, its scene inline (JSON-ready)."""
        return plain_copy({**self.source, "run": _run_table(self.run)})


def load_study(path: str | Path) -> Study:
    """Read and validate a study file (TOML; floats kept as their decimal text).

    Examples
    --------
    >>> import cayley_heyoka as ch
    >>> study = ch.load_study("examples/studies/free_body_grid.toml")  # doctest: +SKIP
    >>> result = ch.run_sweep(study, out="grid.h5")  # doctest: +SKIP
    """
    path = Path(path)
    return Study.from_dict(read_toml(path, "study"), path.parent)


# ---------------------------------------------------------------------- internals: parsing
def _count(value: Any, where: str, most: int | None = None) -> int | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise SceneError(where, f"must be an integer >= 1, got {value!r}")
    if most is not None and value > most:
        raise SceneError(where, f"must be at most {most} (members of a study), got {value}")
    return value


def _required_count(value: Any, where: str, most: int) -> int:
    """A count that must be given (:func:`_count` takes None for an optional one)."""
    count = _count(value, where, most)
    if count is None:
        raise SceneError(where, f"must be an integer >= 1, got {value!r}")
    return count


def _base_scene(spec: Any, base_dir: str | Path | None) -> tuple[dict[str, Any], str | None]:
    if spec is None:
        raise SceneError(
            "scene", "is required: a scene file (path relative to the study) or [scene]"
        )
    if isinstance(spec, str):
        data = read_toml(Path(base_dir or ".") / spec, "scene")
        where = f"scene ({spec})"
    elif isinstance(spec, Mapping):
        data, where = plain_copy(spec), "scene"
    else:
        raise SceneError("scene", f"must be a file path or a table, got {spec!r}")
    try:
        Scene.from_dict(data)
    except SceneError as exc:
        raise SceneError(f"{where}: {exc.field}", exc.constraint) from None
    return data, spec if isinstance(spec, str) else None


def _parameter(
    name: str, spec: Any, kind: str, scene: Mapping[str, Any], prec: Precision
) -> Parameter:
    where = f'sweep.parameters."{name}"'
    path = parse_path(name, where)
    if path[0] == "output":
        raise SceneError(
            where,
            "the output times and lists are the sweep's shared grid and columns; sweep numbers "
            "of the model or the integrator",
        )
    _check_target(scene, path, name, where)
    is_distribution = isinstance(spec, Mapping) and any(k in spec for k in DISTRIBUTIONS)
    if kind == "random":
        if not is_distribution:
            raise SceneError(
                where,
                "a random study needs a distribution: {uniform = [lo, hi]} or "
                f"{{normal = [mean, sd]}}, got {spec!r}",
            )
        check_keys(spec, DISTRIBUTIONS, where)
        if len(spec) != 1:
            raise SceneError(where, f"give one distribution, not {sorted(spec)}")
        ((dist, args),) = spec.items()
        if not isinstance(args, list | tuple) or len(args) != 2:
            raise SceneError(f"{where}.{dist}", f"must be a list of 2 numbers, got {args!r}")
        a = number(args[0], f"{where}.{dist}[0]")
        b = number(args[1], f"{where}.{dist}[1]")
        if dist == "uniform" and exact_fraction(b) <= exact_fraction(a):
            raise SceneError(f"{where}.uniform", f"needs lo < hi, got [{a}, {b}]")
        if dist == "normal" and exact_fraction(b) <= 0:
            raise SceneError(f"{where}.normal", f"needs a standard deviation > 0, got {b}")
        return Parameter(name, path, distribution=(dist, (a, b)))
    if is_distribution:
        raise SceneError(
            where,
            "a distribution belongs to kind = 'random'; a grid takes {start, stop, count} "
            "or a list of values",
        )
    if isinstance(spec, list | tuple):
        if not spec:
            raise SceneError(where, "must not be empty")
        return Parameter(
            name, path, values=tuple(number(v, f"{where}[{i}]") for i, v in enumerate(spec))
        )
    if isinstance(spec, Mapping):
        return Parameter(name, path, values=_grid_values(spec, where, prec))
    raise SceneError(
        where,
        f"must be {{start, stop, count}} (optionally spacing = 'log') or a list, got {spec!r}",
    )


def _grid_values(spec: Mapping[str, Any], where: str, prec: Precision) -> tuple[str, ...]:
    check_keys(spec, ["start", "stop", "count", "spacing"], where)
    missing = [k for k in ("start", "stop", "count") if k not in spec]
    if missing:
        raise SceneError(where, f"a grid needs start, stop and count; missing {missing}")
    start = number(spec["start"], f"{where}.start")
    stop = number(spec["stop"], f"{where}.stop")
    count = _required_count(spec["count"], f"{where}.count", MAX_MEMBERS)
    spacing = spec.get("spacing", "linear")
    if spacing not in ("linear", "log"):
        raise SceneError(f"{where}.spacing", f"must be 'linear' or 'log', got {spacing!r}")
    a, b = exact_fraction(start), exact_fraction(stop)
    if count > 1 and a == b:
        raise SceneError(where, f"start and stop are equal ({start}) but count is {count}")
    if count == 1:
        return (str(start),)
    if spacing == "linear":
        return tuple(_decimal(a + (b - a) * Fraction(k, count - 1), prec) for k in range(count))
    if a <= 0 or b <= 0:
        raise SceneError(where, f"spacing = 'log' needs start and stop > 0, got {start} and {stop}")
    import mpmath

    # Interior points are irrational: text with the digits of fraction_text, in the precision.
    with mpmath.workdps(prec.dps + 15):
        ma = mpmath.mpf(a.numerator) / a.denominator
        ratio = (mpmath.mpf(b.numerator) / b.denominator) / ma
        inner = [
            mpmath.nstr(ma * ratio ** (mpmath.mpf(k) / (count - 1)), prec.dps + 10)
            for k in range(1, count - 1)
        ]
    return (str(start), *inner, str(stop))


def _decimal(value: Fraction, prec: Precision) -> str:
    """Exact decimal text when the fraction has one (denominator 2^a 5^b), else rounded text
    with the digits the precision needs."""
    exact = exact_decimal(value)
    return exact if exact is not None else fraction_text(value, prec)


def _check_target(scene: Mapping[str, Any], path: tuple, name: str, where: str) -> None:
    """The path must lead to one number; keys the base scene leaves out may be added (the
    member scenes' validation checks their names), lists must exist to be indexed."""
    node: Any = scene
    for depth, key in enumerate(path):
        here = show_path(path[:depth]) or "the scene"
        if isinstance(key, int):
            if not isinstance(node, list):
                raise SceneError(where, f"{here} is not a list: it cannot take the index [{key}]")
            if key >= len(node):
                raise SceneError(
                    where, f"index [{key}] is out of range: {here} has {len(node)} entries"
                )
            node = node[key]
            continue
        if not isinstance(node, Mapping):
            raise SceneError(where, f"{here} is a number, not a table")
        if key not in node:
            if any(isinstance(k, int) for k in path[depth:]):
                raise SceneError(
                    where, f"{show_path(path[: depth + 1])} is not in the scene: no list to index"
                )
            return
        node = node[key]
    if isinstance(node, Mapping | list):
        what = "a table" if isinstance(node, Mapping) else "a list"
        hint = f'; name one entry, like "{name}[0]"' if isinstance(node, list) else ""
        raise SceneError(where, f"names {what}, not a number{hint}")


def show_number(value: Any) -> str:
    """A member's value, short: long text to 15 digits (in mpmath: 1e400 has no float)."""
    if isinstance(value, float):
        return f"{value:.6g}"
    text = str(value) if not isinstance(value, int) or abs(value) < 10**20 else shown(value)
    if len(text) <= 20:
        return text
    import mpmath

    with mpmath.workdps(20):
        return mpmath.nstr(scene_mpf(value), 15)


def _run_table(run: RunOptions) -> dict[str, Any]:
    table = {"backend": run.backend, "scheduler": run.scheduler, "workers": run.workers}
    table["chunk"] = run.chunk
    return {k: v for k, v in table.items() if v is not None}


def override_run(run: RunOptions, backend, scheduler, workers, chunk) -> RunOptions:
    table = _run_table(run)
    given = {"backend": backend, "scheduler": scheduler, "workers": workers, "chunk": chunk}
    given = {k: v for k, v in given.items() if v is not None}
    if "scheduler" in given and "backend" not in given:
        given["backend"] = "dask"
    if given.get("backend") == "local":
        table.pop("scheduler", None)
    if "scheduler" in given:
        table.pop("workers", None)
    merged = {**table, **given}
    if not given:
        return run
    named = "--scheduler" if "scheduler" in given else run.scheduler_field
    return RunOptions.parse(merged, "run", named, options=given)
